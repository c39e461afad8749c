#pragma once
// Keyframes for loop closing (seed 000 "closing the loop", seed 002 sec 4): the frames whose
// appearance is indexed for place recognition and whose stereo points re-perceive a place.
//
// Selection rule (KeyframeSelector): frame 0 is a keyframe; after it, a frame becomes a keyframe
// when its estimated left camera has moved, since the last keyframe,
//   |t| >= travel_depth_fraction * median depth of the last keyframe's points   (overlap), or
//   rotation angle >= min_rotation_deg.
// With a camera looking at a scene at depth Z and horizontal field of view h, a translation of
// f * Z parallel to the image leaves about 1 - f / (2 tan(h / 2)) of the view shared: the default
// 0.1 keeps about 90 % overlap at 60 deg (a keyframe every 2.7 m for a blimp at 27 m).
//
// Content (KeyframeBuilder): ORB keypoints of the left image (seed 002's improved ORB,
// features/orb_extractor.hpp) whose 2 x 2 neighbouring pixels have valid dense disparities
// within 1 px of each other (not across a depth edge) become 3D points with covariance: the
// disparity and its sigma bilinearly interpolated at the keypoint's sub-pixel position, then
// reprojected (stereo/reprojection.hpp) with matching_error_px in the image plane (left camera
// frame of the keyframe, m). At most max_points are kept, taken round-robin over the ORB
// bucketing cells (strongest first in each), so they stay spread over the image.
// Memory: a point keeps what it was measured from, 32 (descriptor) + 8 (sub-pixel position) +
// 4 (interpolated disparity) + 4 (its sigma) = 48 bytes, and its 3D point and covariance are
// reprojected from them on demand (point(i): the same reprojectPixel the builder checked them
// with, in double precision, without 36 bytes a point). With the BoW vector
// (8 bytes a word) 400 points and 400 words take 22.4 kB (bytes() gives the figure of one
// keyframe).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "core/camera.hpp"
#include "core/image.hpp"
#include "core/status.hpp"
#include "features/orb_extractor.hpp"
#include "stereo/dense_stereo.hpp"
#include "stereo/reprojection.hpp"

namespace svslam {

// Sparse bag-of-words vector: (word id, tf-idf weight), sorted by word id, L1-normalised.
using BowVector = std::vector<std::pair<std::uint32_t, float>>;

struct Keyframe {
  int id = -1;                  // 0, 1, 2, ... in order of creation
  std::int64_t frame = 0;       // source frame index
  std::int64_t t_ns = 0;        // source timestamp
  // The estimator's world frame T_world_cam is in: 0 from the start, +1 at every reset of the
  // estimator (a new world, the camera at the identity), and when that world began (t_ns of
  // its first frame).
  int world_epoch = 0;
  std::int64_t world_since_t_ns = 0;
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();  // estimate at creation
  // Its covariance ([dtheta, dt], world frame) from the estimator (zero when it has none).
  Eigen::Matrix<double, 6, 6> pose_cov = Eigen::Matrix<double, 6, 6>::Zero();
  std::vector<OrbDescriptor> descriptors;
  std::vector<Eigen::Vector2f> uv_px;              // left image pixel (keypoint, sub-pixel)
  std::vector<float> disparity_px;                 // dense disparity interpolated there, px
  std::vector<float> sigma_d_px;                   // its sigma, px
  // What the points are reprojected with (the builder's calibration and matching error).
  StereoCalibration calib;
  double matching_error_px = 0.5;
  BowVector bow;                                   // filled by the place-recognition side
  float median_depth_m = 0;                        // of the points' z

  std::size_t size() const { return descriptors.size(); }
  // Point i in this keyframe's left camera frame (m) with its covariance (m^2), reprojected
  // from (uv_px, disparity_px, sigma_d_px) with calib and matching_error_px. Precondition:
  // i < size().
  StereoPoint point(std::size_t i) const;
  // Heap bytes held (capacity of every vector) plus the object itself.
  std::size_t bytes() const;
};

struct KeyframeParams {
  double travel_depth_fraction = 0.1;  // new keyframe after this fraction of the median depth, > 0
  double min_travel_m = 0.2;           // ... and never for less than this, m, >= 0
  double min_rotation_deg = 15.0;      // or after this rotation, deg, (0, 180]
  int max_points = 400;                // points kept per keyframe, 16..2000
  double max_point_sigma_m = 2.0;      // sqrt(trace cov) above this: point not kept, m, > 0
  double matching_error_px = 0.5;      // image-plane error of a keypoint, px, > 0
  OrbParams orb = defaultOrb();        // keypoints and descriptors of the left image
  static OrbParams defaultOrb();       // 8 x 6 cells, 16 per cell, FAST threshold 15
  Status validate() const;
};

// Whether a frame is a keyframe (the rule above). Call for every frame, in order.
class KeyframeSelector {
 public:
  explicit KeyframeSelector(const KeyframeParams& params) : params_(params) {}
  bool isKeyframe(const Eigen::Isometry3d& T_world_cam) const;
  // The frame was made a keyframe whose points' median depth is median_depth_m.
  void accept(const Eigen::Isometry3d& T_world_cam, double median_depth_m);
  // Forget the last keyframe: the next frame is one (a new world after a reset).
  void reset() { has_last_ = false; }

 private:
  KeyframeParams params_;
  bool has_last_ = false;
  Eigen::Isometry3d T_world_last_ = Eigen::Isometry3d::Identity();
  double median_depth_m_ = 0;
};

class KeyframeBuilder {
 public:
  KeyframeBuilder(const KeyframeParams& params, const StereoCalibration& calib);
  const Status& initStatus() const { return init_status_; }
  // Builds `out` (its id, frame, t_ns, pose set by the caller) from the rectified left image and
  // its dense disparity (calibration size). failedPrecondition when fewer than 16 points remain.
  Status process(ImageView<const std::uint8_t> left, const DisparityResult& dense, Keyframe& out);

 private:
  bool subpixelPoint(const DisparityResult& dense, float u_px, float v_px, float& d_px,
                     float& sigma_d_px, StereoPoint& out) const;
  KeyframeParams params_;
  StereoCalibration calib_;
  Status init_status_;
  std::unique_ptr<OrbExtractor> orb_;
  std::vector<OrbKeypoint> kp_;
  std::vector<OrbDescriptor> desc_;
  std::vector<int> order_;
  std::vector<float> depths_;
};

}  // namespace svslam
