#pragma once
// Fusion of one frame's dense stereo into the elevation map (seed 001 sec 5.2, with variances).
//
// Every valid disparity d (px) at left pixel (u, v) is a 3D point of the left camera,
//   X_cam = (u - cx, v - cy, f) b / d,
// placed in the map frame (map_frame.hpp) with the estimated pose:
//   p_map = R_map_world (R_world_cam X_cam + t_world_cam).
// Its cell is (floor(x / cell_m), floor(y / cell_m)); its height is z and its grey level the left
// pixel's. Height variance, two parts:
//   disparity (independent from point to point): dh/dd = -(r_z . X_cam) / d, so
//     var_indep = ((r_z . X_cam) / d)^2 sigma_d^2, r_z the map z axis in the camera frame;
//   pose (shared by the frame's points): the pose error is [dtheta, dt] perturbing
//     R_world_cam <- exp([dtheta]x) R_world_cam, t <- t + dt (the estimator's convention), so with
//     q = R_world_cam X_cam and u the map z axis in the world frame,
//     dh = (q x u) . dtheta + u . dt,  var_pose = J P J^T, J = [(q x u)^T, u^T],
//     a quadratic form in X_cam precomputed once per frame.
// Gate: against the cell's estimate before this frame (h_c, var_c), a point whose squared
// Mahalanobis residual r^2 / (var_indep + var_pose + var_c) exceeds gate_chi2 has var_indep
// raised until it sits on the gate: an outlier widens the cell instead of dragging it.
// A frame's points are summed per cell (CellMeasurement), then each cell is fused once.
//
// Preconditions: disparity and left image of the calibration's size. Points that are not
// finite, nearer than min_disparity_px allows or farther than max_range_m never reach the grid.
// A frame whose pose or covariance is not finite is not fused (the reason is returned).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "core/camera.hpp"
#include "core/image.hpp"
#include "core/status.hpp"
#include "map/dem_map.hpp"
#include "map/dem_params.hpp"
#include "stereo/dense_stereo.hpp"

namespace svslam::map {

struct DemFrame {
  ImageView<const std::uint8_t> left;          // rectified left image, grey
  const DisparityResult* disparity = nullptr;  // its dense disparity and sigma_d, px
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();  // world = first left camera
  Eigen::Matrix<double, 6, 6> pose_cov = Eigen::Matrix<double, 6, 6>::Zero();  // [dtheta, dt]
  std::int64_t t_ns = 0;
};

enum class DemSkip { kNone, kPoseNotFinite, kCovarianceNotFinite, kNoDisparity };
const char* toString(DemSkip s);

struct DemFuseStats {
  DemSkip skipped = DemSkip::kNone;  // kNone: the frame was fused
  int points_fused = 0;
  int points_gated = 0;         // fused with an inflated variance
  int points_not_finite = 0;    // NaN / inf disparity sigma, position or variance
  int points_out_of_range = 0;  // d < min_disparity_px, range > max_range_m or too high
  int points_no_tile = 0;       // their tile would exceed max_tiles
  int cells_updated = 0;
  // The fusion sequence number the frame was fused under (tiles' first/last_seq and sources);
  // -1 when it was not (skipped, or no point reached the grid).
  std::int64_t seq = -1;
};

class DemFuser {
 public:
  // Preallocates the point buffer for calib's image size. Error (initStatus) on bad params,
  // calibration or rotation.
  DemFuser(const DemParams& params, const StereoCalibration& calib,
           const Eigen::Matrix3d& R_map_world);
  const Status& initStatus() const { return init_status_; }
  const Eigen::Matrix3d& R_map_world() const { return R_map_world_; }

  // Fuses `in` into `map` (which must have the same params). A skipped frame is not an error:
  // out.skipped says why. Errors: size mismatch, uninitialised fuser.
  Status process(const DemFrame& in, DemMap& map, DemFuseStats& out);

 private:
  struct Point {
    std::int32_t i, j;
    float h_m, var_indep, var_pose;
    std::uint32_t luminance;
  };
  struct Accumulator {
    float ref_h = 0.0f, ref_var = -1.0f;  // the map's estimate before the frame; var < 0: none
    CellMeasurement m;
  };
  void computePoints(const DemFrame& in, DemFuseStats& out);
  void prepareScratch(const DemMap& map);

  DemParams params_;
  StereoCalibration calib_;
  Eigen::Matrix3d R_map_world_ = Eigen::Matrix3d::Identity();
  Status init_status_;
  std::int64_t seq_ = 0;
  std::vector<Point> points_;
  int num_points_ = 0;
  int bi0_ = 0, bj0_ = 0, bcols_ = 0, brows_ = 0;  // bounding box of the frame's cells
  std::vector<Accumulator> scratch_;               // bcols_ x brows_, capacity kept between frames
};

}  // namespace svslam::map
