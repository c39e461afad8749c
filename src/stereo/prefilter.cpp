#include "stereo/prefilter.hpp"

#include <algorithm>
#include <cstring>

namespace svslam {

void xSobelRow(const std::uint8_t* center, std::ptrdiff_t stride, int width, int cap,
               std::uint8_t* out) {
  const std::uint8_t* up = center - stride;
  const std::uint8_t* dn = center + stride;
  for (int x = 0; x < width; ++x) {
    const int s =
        (up[x + 1] + 2 * center[x + 1] + dn[x + 1]) - (up[x - 1] + 2 * center[x - 1] + dn[x - 1]);
    out[x] = static_cast<std::uint8_t>(std::clamp(s, -cap, cap) + cap);
  }
}

void meanRemovalRow(const std::uint8_t* center, std::ptrdiff_t stride, int width, int size, int cap,
                    std::uint32_t* colsum, std::uint8_t* out) {
  const int r = size / 2;
  const int n = width + size - 1;
  const std::uint8_t* top = center - r * stride - r;
  for (int j = 0; j < n; ++j) {
    std::uint32_t s = 0;
    for (int k = 0; k < size; ++k) s += top[k * stride + j];
    colsum[j] = s;
  }
  const std::uint32_t area = static_cast<std::uint32_t>(size * size);
  std::uint32_t sum = 0;
  for (int k = 0; k < size; ++k) sum += colsum[k];
  for (int x = 0; x < width; ++x) {
    if (x > 0) sum += colsum[x + size - 1] - colsum[x - 1];
    const int mean = static_cast<int>((sum + area / 2) / area);
    out[x] = static_cast<std::uint8_t>(std::clamp(center[x] - mean, -cap, cap) + cap);
  }
}

void copyRow(const std::uint8_t* center, int width, std::uint8_t* out) {
  std::memcpy(out, center, static_cast<std::size_t>(width));
}

}  // namespace svslam
