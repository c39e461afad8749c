#include <cmath>

#include "odometry/odometry_params.hpp"

namespace svslam {

Status StereoOdometryParams::validate() const {
  if (Status s = corners.validate(); !s) return s;
  if (detector == PointDetector::kOrb) {
    if (Status s = orb.validate(); !s) return s;
  }
  if (Status s = stereo_match.validate(); !s) return s;
  if (Status s = temporal_match.validate(); !s) return s;
  if (Status s = motion.validate(); !s) return s;
  if (Status s = disparity_offset.validate(); !s) return s;
  if (roi_tracking) {
    if (Status st = clusters.validate(); !st) return st;
    if (!(unknown_threshold_factor > 0.0 && unknown_threshold_factor <= 1.0))
      return Status::invalidArgument("odometry.unknown_threshold_factor must be in (0, 1]");
  }
  if (dense) {
    if (Status s = dense_stereo.validate(); !s) return s;
  }
  if (!(match_sigma_px > 0.0) || !std::isfinite(match_sigma_px))
    return Status::invalidArgument("odometry.match_sigma_px must be > 0");
  if (dense && match_sigma_px != 0.5 && match_sigma_px != 1.0)
    return Status::invalidArgument(
        "odometry.match_sigma_px must be 0.5 or 1 with dense stereo (8-neighbour observation)");
  if (!(min_disparity_px > 0.0) || !std::isfinite(min_disparity_px))
    return Status::invalidArgument("odometry.min_disparity_px must be > 0");
  if (!(max_depth_m > 0.0)) return Status::invalidArgument("odometry.max_depth_m must be > 0");
  if (min_matches < 3) return Status::invalidArgument("odometry.min_matches must be >= 3");
  if (!(lost_search_radius_px > 0.0f) || !std::isfinite(lost_search_radius_px))
    return Status::invalidArgument("odometry.lost_search_radius_px must be > 0");
  if (!(repredict_px > 0.0) || !std::isfinite(repredict_px))
    return Status::invalidArgument("odometry.repredict_px must be > 0");
  if (Status s = rotation_alignment.validate(); !s) return s;
  return Status::ok();
}

}  // namespace svslam
