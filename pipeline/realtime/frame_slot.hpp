#pragma once
// One frame's worth of pipeline state, preallocated in a pool and handed from stage to stage by
// pointer: the captured pair, the stereo stage's product, the estimator's result and steady-
// clock stamps at each stage boundary (ns). Buffers keep their capacity between frames, so a
// slot allocates nothing once warm.
#include <Eigen/Geometry>
#include <array>
#include <cstdint>

#include "core/status.hpp"
#include "drivers/source/stereo_source.hpp"
#include "odometry/stereo_stage.hpp"
#include "slam/estimator.hpp"

namespace svslam::rt {

// Steady-clock times (ns since the clock's epoch) of one frame's passage.
struct FrameStamps {
  static constexpr int kMaxStages = 8;  // processing stages after the source
  std::int64_t capture_ns = 0;     // capture instant: when due (paced replay), else when in memory
  std::int64_t read_start_ns = 0;  // the source's read began
  std::int64_t captured_ns = 0;    // pair in memory
  std::array<std::int64_t, kMaxStages> start_ns{}, end_ns{};  // per stage of the graph
};

struct FrameSlot {
  drivers::StereoFrame frame;  // index, t_ns (the source's timestamp), rectified grey pair
  std::int64_t seq = 0;        // capture sequence number (a gap downstream = a dropped frame)
  bool has_ground_truth = false;
  Eigen::Isometry3d T_gt_first_cam = Eigen::Isometry3d::Identity();
  StereoStageOutput stereo;
  SlamFrameResult result;
  // The estimator's world frame result is in: 0 from the start, +1 at every reset (set by the
  // estimator stage).
  int world_epoch = 0;
  FrameStamps stamps;
  bool failed = false;  // a stage failed on this frame or an earlier one: not published
};

}  // namespace svslam::rt
