#pragma once
// The per-frame stereo stage of the odometry: what can be computed from one rectified pair
// alone, with no state carried between frames, so that a pipeline can run it on its own thread
// ahead of the tracking (seed 001 sec. 3.1 and 3.2):
//  1. optional dense census stereo (the disparity prior and the 8-neighbour observation);
//  2. interest points in the left image (precise Harris / Shi-Tomasi with grid bucketing, or
//     the ORB of seed 002);
//  3. stereo matching of the points along the row (ZNCC, ratio, continuity, recovery).
// With clustered-feature ROI tracking (seed 004), steps 2-3 depend on the previous frame's
// clusters: process() then stops after step 1 (`matched` stays false) and the odometry runs
// detect() and match() itself with its ROIs.
// Two StereoStage objects built from the same parameters give identical outputs for the same
// pair (the threaded pipeline's stage and the odometry's own one), whatever the executor.
#include <Eigen/Core>
#include <memory>
#include <vector>

#include "core/camera.hpp"
#include "core/executor.hpp"
#include "core/image.hpp"
#include "core/stage_observer.hpp"
#include "core/status.hpp"
#include "odometry/odometry_params.hpp"

namespace svslam {

// The product of the stereo stage for one pair. Buffers are reused from frame to frame.
struct StereoStageOutput {
  bool has_disparity = false;  // dense stereo ran (params.dense)
  DisparityResult disparity;   // left-image disparity and sigma_d, px
  bool matched = false;        // steps 2-3 ran (false in ROI mode: left to the odometry)
  std::vector<Eigen::Vector2f> corner_px;  // detected points, left image, px
  std::vector<float> corner_resp;          // their detector responses
  float max_response = 0.0f;               // strongest corner response of the image (Harris)
  std::vector<StereoMatch> stereo;         // stereo matches of the points
  StereoMatchStats stereo_stats;
  // Clears the per-frame content, keeping the capacity.
  void clear();
};

class StereoStage {
 public:
  // `params` are the odometry's; the stage uses detector, corners (at the lowered ROI threshold
  // when roi_tracking), orb, stereo_match, dense and dense_stereo. Preallocates for the size.
  StereoStage(const StereoOdometryParams& params, const StereoCalibration& calib);
  ~StereoStage();
  StereoStage(const StereoStage&) = delete;
  StereoStage& operator=(const StereoStage&) = delete;
  const Status& initStatus() const { return init_status_; }

  // Steps 1-3 (steps 2-3 skipped in ROI mode). `observer` hears "dense_stereo" (when enabled),
  // "detect" and "stereo_match". Images of the calibration size.
  Status process(ImageView<const std::uint8_t> left, ImageView<const std::uint8_t> right,
                 StereoStageOutput& out, Executor& executor, StageObserver* observer = nullptr);
  // Step 2 alone: fills corner_px, corner_resp, max_response. The corner filtering runs over
  // row stripes on `executor` (same corners for any executor).
  Status detect(ImageView<const std::uint8_t> left, StereoStageOutput& out, Executor& executor);
  // Step 3 alone over out.corner_px; `prior` is the dense disparity (empty view: none) and
  // `ranges` (optional, one per point) bound the disparity search (ROI tracking).
  Status match(ImageView<const std::uint8_t> left, ImageView<const std::uint8_t> right,
               ImageView<const float> prior, const std::vector<Eigen::Vector2i>* ranges,
               StereoStageOutput& out);

 private:
  StereoOdometryParams params_;
  StereoCalibration calib_;
  Status init_status_;
  CornerDetector detector_;
  std::unique_ptr<OrbExtractor> orb_;
  std::vector<OrbKeypoint> orb_kp_;
  std::vector<OrbDescriptor> orb_desc_;
  std::vector<Corner> corners_;
  StereoPointMatcher stereo_matcher_;
  std::unique_ptr<DenseStereo> dense_;
  std::size_t max_points_ = 0;  // bound of the points detected per frame
};

}  // namespace svslam
