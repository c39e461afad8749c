#pragma once
// The texture filter of the dense stereo stage (as OpenCV StereoBM's): a pixel is rejected when
// the sum over its aggregation window of the central-difference gradient |I(x+1) - I(x-1)| of
// the left image is below a limit. Column sums are kept as a running sum over rows.
#include <cstdint>

namespace svslam {

// col_sums[x] += sign * |row[x + 1] - row[x - 1]| for x in [0, width) (mod 2^32: adding then
// subtracting the same row restores the sums). Precondition: row readable at [-1, width + 1).
void addRowGradients(const std::uint8_t* row, int width, int sign, std::uint32_t* col_sums);

// low[x] = 1 when sum_{k=-radius}^{radius} col_sums[clamp(x + k, 0, width - 1)] < limit, else 0.
void markLowTexture(const std::uint32_t* col_sums, int width, int radius, double limit,
                    std::uint8_t* low);

}  // namespace svslam
