#pragma once
// The loop-closing stages of `svslam run` (seed 000 "closing the loop", seed 002 sec 4;
// src/loop/loop_closer.hpp):
//  - front end, on the after-publication thread beside the mapper: the keyframe rule, the
//    keyframe's ORB points with their dense-stereo 3D covariance, the odometry covariance since
//    the previous keyframe; each keyframe is handed to
//  - the back end, a thread of its own behind a lock-free SPSC ring of keyframes: place
//    recognition, geometric verification, PCM, and the Ceres pose graph. It never blocks the
//    estimator (only the after-publication thread waits when the ring is full). After each
//    solution a pose_correction_t goes out on LCM (lcm.correction_channel) with the keyframes
//    whose correction changed.
// At the end of the run (after the last keyframe is processed): trajectory_optimized_kitti.txt
// and trajectory_optimized_tum.txt, the published trajectory (trajectory_tum.txt) with every
// pose moved by the correction of its time (LoopCloser::correctionAt).
// Determinism: the back end sees every keyframe in order and feeds nothing back into the
// estimator, so its output does not depend on thread timing when the front end sees every frame
// (as fast as possible); live, frames the after-publication thread skips are not keyframe
// candidates.
#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>

#include "core/status.hpp"
#include "drivers/lcm/lcm_transport.hpp"
#include "drivers/source/stereo_source.hpp"
#include "pipeline/config/run_config.hpp"
#include "pipeline/realtime/frame_slot.hpp"
#include "pipeline/run/run_outputs.hpp"

namespace svslam::rt {

// Whether this build has the pose-graph back end (Ceres).
bool loopClosingAvailable();

class LoopStage {
 public:
  LoopStage(const config::RunConfig& cfg, drivers::StereoSource& source, std::string out_dir,
            drivers::LcmLink* lcm);
  ~LoopStage();  // stops and joins the back end
  LoopStage(const LoopStage&) = delete;
  LoopStage& operator=(const LoopStage&) = delete;
  // Loads loop.vocabulary, builds the front end and the closer, starts the back-end thread.
  Status init();
  // After-publication thread: one published frame.
  Status process(FrameSlot& slot);
  // After the run: drains the back end, joins it, writes the optimised trajectory files.
  Status finish();
  // stats.json's "loop" object.
  std::string json() const;
  const run::StageTimes& times() const { return times_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  run::StageTimes times_;
};

}  // namespace svslam::rt
