#include "map/hillshade.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "map/dem_raster_check.hpp"

namespace svslam::map {

Status HillshadeParams::validate() const {
  if (!std::isfinite(azimuth_deg))
    return Status::invalidArgument("hillshade: azimuth_deg must be finite");
  if (!(altitude_deg >= 0.0 && altitude_deg <= 90.0))
    return Status::invalidArgument("hillshade: altitude_deg must be in [0, 90]");
  if (!std::isfinite(z_factor) || z_factor <= 0.0)
    return Status::invalidArgument("hillshade: z_factor must be finite and > 0");
  return Status::ok();
}

Result<std::vector<std::uint8_t>> hillshade(const DemRaster& dem, const HillshadeParams& params) {
  if (Status s = checkDemRaster(dem, "hillshade"); !s) return s;
  if (Status s = params.validate(); !s) return s;
  constexpr double kDeg = std::numbers::pi / 180.0;
  const double az = params.azimuth_deg * kDeg, alt = params.altitude_deg * kDeg;
  const double sx = std::sin(az) * std::cos(alt), sy = std::cos(az) * std::cos(alt);
  const double sz = std::sin(alt);
  const double scale = params.z_factor / (8.0 * dem.cell_m);

  std::vector<std::uint8_t> out(dem.height_m.size(), 0);
  for (int r = 1; r + 1 < dem.rows; ++r) {
    for (int c = 1; c + 1 < dem.cols; ++c) {
      double w[3][3];  // w[dr + 1][dc + 1]: height at row r + dr, column c + dc
      bool valid = true;
      for (int dr = -1; dr <= 1 && valid; ++dr)
        for (int dc = -1; dc <= 1; ++dc) {
          w[dr + 1][dc + 1] = dem.height_m[dem.index(c + dc, r + dr)];
          if (!std::isfinite(w[dr + 1][dc + 1])) {
            valid = false;
            break;
          }
        }
      if (!valid) continue;
      const double p =
          ((w[0][2] + 2 * w[1][2] + w[2][2]) - (w[0][0] + 2 * w[1][0] + w[2][0])) * scale;
      const double q =
          ((w[0][0] + 2 * w[0][1] + w[0][2]) - (w[2][0] + 2 * w[2][1] + w[2][2])) * scale;
      const double shade = (sz - p * sx - q * sy) / std::sqrt(1.0 + p * p + q * q);
      // (A huge height step makes p or q infinite and the shade NaN: a wall, shown as shadow.)
      const double level = 1.0 + 254.0 * (std::isfinite(shade) ? std::clamp(shade, 0.0, 1.0) : 0.0);
      out[dem.index(c, r)] = static_cast<std::uint8_t>(std::lround(level));
    }
  }
  return out;
}

}  // namespace svslam::map
