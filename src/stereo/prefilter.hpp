#pragma once
// Prefilters of the SAD matching cost (as OpenCV StereoBM does), computed one row at a time on
// an image padded by at least (size / 2) pixels (mean removal) or 1 pixel (x-Sobel) on every
// side. Output values lie in [0, 2 cap].
#include <cstddef>
#include <cstdint>

namespace svslam {

// x-Sobel: s = [I(x+1,y-1) + 2 I(x+1,y) + I(x+1,y+1)] - [same at x-1]; out = clamp(s,-cap,cap)+cap.
// `center` points at pixel (0, y) of the padded image, `stride` in bytes.
void xSobelRow(const std::uint8_t* center, std::ptrdiff_t stride, int width, int cap,
               std::uint8_t* out);

// Mean removal: out = clamp(I(x,y) - round(mean of the size x size window), -cap, cap) + cap.
// `colsum` is scratch of width + size - 1 entries.
void meanRemovalRow(const std::uint8_t* center, std::ptrdiff_t stride, int width, int size, int cap,
                    std::uint32_t* colsum, std::uint8_t* out);

// Copy of a grey row: out[x] = center[x].
void copyRow(const std::uint8_t* center, int width, std::uint8_t* out);

}  // namespace svslam
