// DemParams::validate (dem_params.hpp): each field against its documented range.
#include "map/dem_params.hpp"

#include <string>

#include "map/map_frame.hpp"

namespace svslam::map {

Status DemParams::validate() const {
  auto bad = [](const std::string& field, const std::string& what) {
    return Status::invalidArgument("map." + field + " " + what);
  };
  if (!(cell_m > 0.001 && cell_m <= 100.0)) return bad("cell_m", "must be in (0.001, 100] m");
  Eigen::Matrix3d R_map_world;  // finite, non-zero, not parallel to the camera x axis
  if (Status s = mapRotationFromGravity(gravity_in_first_camera, R_map_world); !s) return s;
  if (tile_cells < 8 || tile_cells > 1024) return bad("tile_cells", "must be in [8, 1024]");
  if (!(std::isfinite(max_range_m) && max_range_m > 0.0))
    return bad("max_range_m", "must be finite and > 0 m");
  if (!(std::isfinite(min_disparity_px) && min_disparity_px > 0.0))
    return bad("min_disparity_px", "must be finite and > 0 px");
  if (!(gate_chi2 > 0.0 && gate_chi2 <= 1e6)) return bad("gate_chi2", "must be in (0, 1e6]");
  if (!(reject_variance_factor >= 1.0 && reject_variance_factor <= 1e3))
    return bad("reject_variance_factor", "must be in [1, 1e3]");
  if (!std::isfinite(max_height_above_camera_m))
    return bad("max_height_above_camera_m", "must be finite (m)");
  if (!(std::isfinite(min_sigma_m) && min_sigma_m >= 0.0))
    return bad("min_sigma_m", "must be finite and >= 0 m");
  if (max_tiles < 1) return bad("max_tiles", "must be >= 1");
  if (max_raster_mcells < 1 || max_raster_mcells > 4096)
    return bad("max_raster_mcells", "must be in [1, 4096]");
  return Status::ok();
}

}  // namespace svslam::map
