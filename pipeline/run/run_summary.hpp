#pragma once
// What `svslam run` accumulates over the frames and writes to stats.json.
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "drivers/lcm/command_gate.hpp"
#include "pipeline/config/run_config.hpp"
#include "pipeline/realtime/pipeline_runner.hpp"
#include "pipeline/run/run_outputs.hpp"
#include "slam/estimator.hpp"

namespace svslam::run {

struct RunSummary {
  int frames = 0;
  int tracked = 0;
  std::map<std::string, int> failure_counts;
  std::vector<std::pair<int, std::string>> failures;  // the first ones: frame + reason
  double sum_corners = 0, sum_points = 0, sum_matches = 0, sum_inliers = 0;
  double sum_recovered = 0, sum_continuity_rejected = 0;
  // Landmark map (ekf mode; zero otherwise).
  double sum_observed = 0, sum_reperceived = 0, sum_gated = 0, sum_in_state = 0;
  double sum_motion_m2 = 0;    // squared motion_rms_mahalanobis of the estimated motions
  int motion_frames = 0;      // frames with an estimated motion
  double disparity_offset_px = 0;  // the odometry's estimate after the last frame
  int disparity_offset_frames = 0;  // frames that contributed to it
  int repredicted = 0;        // frames whose temporal search was re-predicted
  int retried = 0;            // frames whose temporal search was retried around the identity
  double sum_nis = 0;         // d^2 of the accepted landmark observations
  std::int64_t nis_count = 0;  // accepted landmark observations
  double sum_visible = 0, sum_no_match = 0, sum_no_stereo = 0;
  int max_in_state = 0, landmarks_in_map = 0, added = 0, retired = 0, restored = 0;
  // Camera loss (slam_system.hpp): frames processed from the left image alone, the times the
  // right camera became unusable, each frame's RightCameraState (ok, missing, flat, frozen),
  // landmarks initialised from bearings, bearings accepted and their d^2 (2 dof each).
  int mono_frames = 0, right_camera_losses = 0, bearing_added = 0;
  int mono_initializing = 0;  // monocular frames before the two-view start (no map, no pose)
  int resumed_untracked = 0;  // first stereo frames after mono ones the odometry did not track
  // Relocalisation (slam/relocaliser.hpp): lost frames, relocalisations (and the inliers of
  // the last), searches that failed.
  int frames_lost = 0, relocalisations = 0, relocalisation_failures = 0;
  int last_relocalisation_frame = -1, last_relocalisation_inliers = 0;
  int relocalised_untracked = 0;  // relocalised frames without a frame-to-frame motion
  std::int64_t bearing_count = 0;
  double sum_bearing_nis = 0;
  std::int64_t right_camera_state_counts[4] = {0, 0, 0, 0};
  bool prev_mono_ = false;
  // Frames of the recording the source left out (kitti: one side missing) and their names.
  int source_frames_skipped = 0;
  std::string source_frames_skipped_detail;
  // The source's own counters (StereoSource::counters(): live cameras), in its order.
  std::vector<std::pair<std::string, std::int64_t>> source_counters;
  // LCM commands received (accepted, refused by reason); empty when LCM is off.
  std::optional<drivers::CommandCounts> lcm_commands;
  // Altimeter readings received and rejected on LCM (mono_scale altitude; -1 when not read),
  // and the frame whose two-view start took its unit from one (-1: none).
  std::int64_t altitude_readings = -1, altitude_rejected = -1;
  int altitude_scaled_frame = -1;

  // Adds one processed frame (source index `frame`).
  void add(int frame, const SlamFrameResult& r);
};

// stats.json: the run's configuration summary, the per-frame means, the per-stage times
// (`times`: algorithm stages, ms) and the pipeline's report (stage latencies, end-to-end
// latency capture -> pose published, queues, drops, frames per second); the landmark figures
// when the estimator keeps a landmark map (`outputs`).
std::string statsJson(const config::RunConfig& cfg, const std::string& source, const RunSummary& s,
                      EstimatorOutputs outputs, const StageTimes& times,
                      const rt::PipelineReport& pipeline, const std::string& error,
                      const std::string& map_json = "", const std::string& loop_json = "");

}  // namespace svslam::run
