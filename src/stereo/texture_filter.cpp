#include "stereo/texture_filter.hpp"

#include <algorithm>
#include <cstdlib>

namespace svslam {

void addRowGradients(const std::uint8_t* row, int width, int sign, std::uint32_t* col_sums) {
  for (int x = 0; x < width; ++x)
    col_sums[x] += static_cast<std::uint32_t>(sign * std::abs(row[x + 1] - row[x - 1]));
}

void markLowTexture(const std::uint32_t* col_sums, int width, int radius, double limit,
                    std::uint8_t* low) {
  // Running horizontal box, borders replicated.
  std::uint32_t sum = 0;
  for (int k = -radius; k <= radius; ++k) sum += col_sums[std::clamp(k, 0, width - 1)];
  for (int x = 0; x < width; ++x) {
    if (x > 0) {
      sum += col_sums[std::min(x + radius, width - 1)];
      sum -= col_sums[std::max(x - radius - 1, 0)];
    }
    low[x] = static_cast<std::uint8_t>(static_cast<double>(sum) < limit);
  }
}

}  // namespace svslam
