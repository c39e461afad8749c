#pragma once
// Trajectory files: KITTI odometry poses (one 3x4 row-major [R|t] per line, frame index =
// line), TUM (t tx ty tz qx qy qz qw; t in seconds, or in nanoseconds when > 1e12 as in the
// EuRoC per-frame ground truth of ../shared/data), and EuRoC's camera extrinsic T_BS
// (sensor.yaml). Errors name the file and the line.
#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "core/status.hpp"
#include "core/time.hpp"

namespace svslam::drivers {

enum class TrajectoryFormat { kKitti, kTum };

struct TrajectoryFile {
  TrajectoryFormat format = TrajectoryFormat::kKitti;
  std::vector<TimeNs> t_ns;              // TUM only (empty for KITTI)
  std::vector<Eigen::Isometry3d> poses;  // T_world_frame
};

// Largest max |R^T R - I| of a KITTI rotation, and | |q| - 1 | of a TUM quaternion, accepted
// (and projected onto the nearest rotation); beyond, the line is an error.
inline constexpr double kRotationTolerance = 1e-3;

// Reads a KITTI or TUM file, recognised by the number of values on the first data line (12 or
// 8). '#' starts a comment. Every line must have the same format and finite values, a rotation
// (kRotationTolerance) and, for TUM, a time stamp within the range of int64 nanoseconds.
Result<TrajectoryFile> readTrajectory(const std::string& path);
// The same from the file's text (readTrajectory reads the file, then calls this); `path` names
// the file in errors.
Result<TrajectoryFile> parseTrajectory(const std::string& text, const std::string& path);

// T_BS (sensor to body) from an EuRoC sensor.yaml: the 16 numbers after "data:" under "T_BS:".
Result<Eigen::Isometry3d> readEurocTbs(const std::string& sensor_yaml);
// The same from the text of sensor.yaml; `sensor_yaml` names the file in errors.
Result<Eigen::Isometry3d> parseEurocTbs(const std::string& text, const std::string& sensor_yaml);

// Pairs the poses of two trajectories: by index when either has no timestamps (then the counts
// must match), else each estimate stamp with the nearest ground-truth stamp within max_dt_s.
// est_index, when given, receives the index in `est` of each pair.
Status associateTrajectories(const TrajectoryFile& gt, const TrajectoryFile& est, double max_dt_s,
                             std::vector<Eigen::Isometry3d>& gt_out,
                             std::vector<Eigen::Isometry3d>& est_out,
                             std::vector<std::size_t>* est_index = nullptr);

}  // namespace svslam::drivers
