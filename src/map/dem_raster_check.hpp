#pragma once
// The preconditions every consumer of a DemRaster (hillshade, scoring, files) checks first, so
// that a malformed raster is an error value instead of an out-of-bounds read.
#include <climits>
#include <cmath>
#include <string>

#include "core/status.hpp"
#include "map/dem_raster.hpp"

namespace svslam::map {

// ok when cell_m is finite and > 0, cols, rows >= 0, the map indices of every cell fit in an
// int, and height_m, sigma_m and count hold rows * cols values (luminance is checked by whoever
// needs it). `what` names the raster in the message ("estimate", "ground truth", ...).
inline Status checkDemRaster(const DemRaster& r, const std::string& what) {
  if (!std::isfinite(r.cell_m) || r.cell_m <= 0)
    return Status::invalidArgument(what + ": cell size must be finite and > 0, got " +
                                   std::to_string(r.cell_m) + " m");
  if (r.cols < 0 || r.rows < 0)
    return Status::invalidArgument(what + ": negative size " + std::to_string(r.cols) + " x " +
                                   std::to_string(r.rows));
  if (static_cast<long long>(r.i0) + r.cols > INT_MAX ||
      static_cast<long long>(r.j0) + r.rows > INT_MAX)
    return Status::invalidArgument(what + ": map indices overflow (i0 + cols or j0 + rows)");
  const std::size_t n = static_cast<std::size_t>(r.cols) * static_cast<std::size_t>(r.rows);
  if (r.height_m.size() != n || r.sigma_m.size() != n || r.count.size() != n)
    return Status::invalidArgument(what + ": bands hold " + std::to_string(r.height_m.size()) +
                                   "/" + std::to_string(r.sigma_m.size()) + "/" +
                                   std::to_string(r.count.size()) +
                                   " values (height/sigma/count) for " + std::to_string(r.cols) +
                                   " x " + std::to_string(r.rows) + " cells");
  return Status::ok();
}

}  // namespace svslam::map
