#pragma once
// The estimator: what turns each frame's stereo stage output into a pose. One call per frame;
// the pipeline's estimator stage and the offline tools drive every mode through this interface.
//   vo   StereoOdometry: temporal matching + visual motion estimation chained frame to frame
//        (slam/vo_estimator.hpp);
//   ekf  SlamSystem: the same front end predicting an EKF over the pose and 3D landmarks
//        (slam/slam_system.hpp);
//   mono SlamSystem from the left camera alone, bearing observations; the first pair's stereo
//        points give the scale, or (slam.mono_scale none) a two-view start from the left
//        camera alone gives a map up to scale (slam_system.hpp, "Monocular mode").
// Every estimator also returns the feedback the stereo stage of the next frame needs (the
// predicted motion for clustered-feature ROI tracking).
#include <memory>
#include <vector>

#include "core/camera.hpp"
#include "core/executor.hpp"
#include "core/image.hpp"
#include "core/stage_observer.hpp"
#include "core/status.hpp"
#include "odometry/stereo_odometry.hpp"
#include "odometry/stereo_stage.hpp"
#include "slam/landmark_manager.hpp"
#include "slam/slam_params.hpp"

namespace svslam {

enum class EstimatorKind { kEkf, kVo, kMono };

struct SlamFrameResult {
  OdometryFrameResult odometry;  // front end + VME (T_first_cam there is pure odometry)
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();  // the estimate
  // Covariance published with the pose, [rot rad, trans m]: the filter's pose covariance
  // (ekf); the last frame-to-frame motion's (vo, which has no pose covariance).
  Eigen::Matrix<double, 6, 6> pose_cov = Eigen::Matrix<double, 6, 6>::Zero();
  // What the errors the filter does not estimate add to the pose covariance ("consider"
  // parameters: the calibration's uncertainty, slam/calibration_consider.hpp, and the
  // odometry's rotational drift, slam/drift_consider.hpp; ekf, mono; zero for vo and exact
  // calibrations). Published (LCM, pose_covariance.txt) as pose_cov + pose_cov_consider; the
  // filter, the map and loop closing use pose_cov.
  Eigen::Matrix<double, 6, 6> pose_cov_consider = Eigen::Matrix<double, 6, 6>::Zero();
  int landmarks_in_state = 0;
  int landmarks_in_map = 0;   // in the state + retired
  int observed = 0;           // landmarks observed (tracked from the previous frame)
  int reperceived = 0;        // landmarks found again by re-perception
  int predicted_visible = 0;  // landmarks of the state predicted inside the image
  int search_no_match = 0;    // ... not found in the left image (ZNCC)
  int search_no_stereo = 0;   // ... found, but not in the right image
  int gated = 0;              // observations rejected by the chi-square gate
  // Innovation statistics of the accepted observations: the sum of their normalised innovation
  // squared d^2 = nu^T S^-1 nu (3 dof each; a consistent filter averages 3 per observation,
  // a little less after the gate) and their number.
  double nis_sum = 0;
  int nis_count = 0;
  int added = 0;
  int retired = 0;
  int restored = 0;  // retired anchored landmarks put back into the state
  int candidates = 0;
  int vme_matches = 0;  // matches given to the VME (non-landmarks)
  // Camera loss: mono = the right image was not used for this frame (the pose comes from
  // bearing observations of the map); right_camera = RightCameraState of this frame's right
  // image (0 ok, 1 missing, 2 flat, 3 frozen). Bearings accepted and the sum of their d^2
  // (2 dof each); landmarks initialised from bearings.
  bool mono = false;
  // Monocular mode without a scale source, before its two-view start: no map, no pose (the
  // world origin is published with an uninformative covariance; mono is also set).
  bool initializing = false;
  bool altitude_scaled = false;  // this frame's two-view start took its unit from the altimeter
  bool stereo_resumed = false;  // first stereo frame after mono ones (predicted by the filter:
                                // the odometry's previous frame is stale and may fail)
  int right_camera = 0;
  // Relocalisation (slam/relocaliser.hpp): the frame was lost (no motion, too few landmarks, or
  // a loss still going on), its pose was found against a kept keyframe (with that many
  // inliers), or a search failed.
  bool lost = false;
  bool relocalised = false;
  bool relocalisation_failed = false;
  int relocalisation_inliers = 0;
  double bearing_nis_sum = 0;
  int bearing_count = 0;
  int bearing_added = 0;
  int mono_candidates = 0;
};

// What an estimator produces beyond the pose (which outputs a run writes).
struct EstimatorOutputs {
  bool pose_covariance = false;  // pose_cov is a covariance of the pose (pose_covariance.txt)
  bool landmark_map = false;     // map() holds landmarks (landmarks.ply, the map summary)
};

class Estimator {
 public:
  virtual ~Estimator() = default;
  virtual const Status& initStatus() const = 0;
  virtual EstimatorOutputs outputs() const = 0;
  // One rectified pair (calibration size) and the stereo stage's output for it (a StereoStage
  // built from the same odometry parameters, fed with this estimator's feedback(); kept alive
  // and unchanged until the next call). `out` is overwritten. The executor splits the work that
  // splits (results do not depend on it); `observer` hears the sub-stages.
  virtual Status process(ImageView<const std::uint8_t> left, ImageView<const std::uint8_t> right,
                         const StereoStageOutput& stereo, SlamFrameResult& out, Executor& executor,
                         StageObserver* observer = nullptr) = 0;
  // For the stereo stage of the next frame.
  virtual TrackingFeedback feedback() const = 0;
  // The camera's height above the ground (m, from an altimeter) at the coming frame, for the
  // monocular mode's scale (slam.mono_scale = altitude); ignored by the other estimators and
  // when not finite and > 0. Holds until replaced.
  virtual void setAltitude(double altitude_m) { (void)altitude_m; }
  // Every landmark ever initialised (empty without a landmark map).
  virtual std::vector<MapLandmark> map() const { return {}; }
  // Loop closing's correction (pipeline/realtime/loop_stage.hpp): the back end puts the current
  // pose at C_new_old T_world_cam with covariance cov_world ([dtheta, dt], world frame).
  //   ekf: the corrected position as a measurement (EkfSlam::updatePosition): the filter moves
  //        as far as that covariance against its own says, its attitude and the landmarks of
  //        the state with it through their cross covariances, and its covariance shrinks;
  //   vo:  the chained pose moves by C_new_old (it has no covariance to weigh it with).
  // `moved` receives the world-frame move of the pose, T_after T_before^-1. Landmarks out of the
  // state stay where they are (anchors are in the frame of the first pose, which loop closing
  // holds fixed). invalidArgument when C_new_old is not a finite rigid transform or cov_world
  // not symmetric positive definite (nothing moves).
  virtual Status applyLoopCorrection(const Eigen::Isometry3d& C_new_old,
                                     const Matrix6d& cov_world, Eigen::Isometry3d& moved) = 0;
};

// The estimator of a kind; check initStatus() (invalid parameters or calibration).
std::unique_ptr<Estimator> makeEstimator(EstimatorKind kind, const SlamSystemParams& slam,
                                         const StereoOdometryParams& odometry,
                                         const StereoCalibration& calib);

// The stereo stage and an estimator chained on the calling thread, one pair after the other:
// what the pipeline's stereo and estimator stages do to each frame, for tests, benchmarks and
// tools. The pipeline itself owns its stage and estimator and does not use this.
class FrameByFrame {
 public:
  FrameByFrame(const StereoOdometryParams& odometry, const StereoCalibration& calib,
               std::unique_ptr<Estimator> estimator);
  Status initStatus() const;
  Status process(ImageView<const std::uint8_t> left, ImageView<const std::uint8_t> right,
                 SlamFrameResult& out, Executor& executor, StageObserver* observer = nullptr);
  Estimator& estimator() { return *estimator_; }
  const StereoStageOutput& stereo() const { return stereo_; }

 private:
  StereoStage stage_;
  StereoStageOutput stereo_;
  std::unique_ptr<Estimator> estimator_;
};

}  // namespace svslam
