#pragma once
// The loop-closing stages of `svslam run` (seed 000 "closing the loop", seed 002 sec 4;
// src/loop/loop_closer.hpp):
//  - front end, on the after-publication thread beside the mapper: the keyframe rule, the
//    keyframe's ORB points with their dense-stereo 3D covariance, the odometry covariance since
//    the previous keyframe; each keyframe is handed to
//  - the back end, a thread of its own behind a lock-free SPSC ring of keyframes: place
//    recognition, geometric verification, PCM, and the Ceres pose graph, at nice +10. Live it
//    never blocks the estimator (only the after-publication thread waits when the ring is
//    full); replayed as fast as possible the estimator waits for it (Determinism). After each
//    solution a pose_correction_t goes out on LCM (lcm.correction_channel) with the keyframes
//    whose correction changed.
// Feedback (loop.feedback): a solution made when the back end handled keyframe K (source frame
// f_K) corrects the estimator before frame f_K + D is estimated (D = loop.feedback_delay_frames;
// Estimator::applyLoopCorrection). Its correction of keyframe K, C_K = T_corrected_K
// T_online_K^-1, maps an online pose of f_K's time; moves already applied after f_K are in the
// estimator's frame but not in T_online_K, so the correction given is
//     C = C_K B^-1,   B = M_m ... M_1 (the moves the estimator made at frames after f_K),
// with the covariance of the corrected pose of K to first order from the newest accepted loop
// (query q, candidate c): T_world_K = T_world_c Z_qc^-1 T_q_(q+1) ... T_(K-1)_K, the product's
// Jacobians (loop/relative_pose.hpp) applied to the estimator's covariance of c when it was made
// (an upper bound of what the graph knows of it), the loop's and the odometry edges'.
// At the end of the run (after the last keyframe is processed): trajectory_optimized_kitti.txt
// and trajectory_optimized_tum.txt, the published trajectory (trajectory_tum.txt) with every
// pose moved by the correction of its time (LoopCloser::correctionAt), and
// landmarks_optimized.ply: every landmark of the map moved the same way from the keyframe at or
// before the frame it was last seen (C_k B_s^-1, B_s the moves applied after f_k up to then);
// the mapper re-places the elevation map with the same corrections (frameCorrection,
// dem_optimized.tif: map_stage.hpp).
// Resets: every frame carries the estimator's world_epoch; the front end starts a new world at
// its first frame (loop_closer.hpp "Resets"), solutions for keyframes of an older world are
// never fed back, and a frame of a new world before that world's first keyframe takes that
// keyframe's correction (none when there is none yet).
// Determinism: the back end sees every keyframe in order; replayed as fast as possible the
// front end sees every frame and the estimator, before frame f, waits until the back end has
// handled every keyframe made up to frame f - D, so which moves apply where does not depend on
// thread timing (threaded == --sequential). Live (frames may be skipped) a solution is applied
// at the first frame at or after f_K + D at which it is ready: the estimator never waits.
#include <Eigen/Geometry>
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <thread>

#include "core/status.hpp"
#include "drivers/lcm/lcm_transport.hpp"
#include "drivers/source/stereo_source.hpp"
#include "pipeline/config/run_config.hpp"
#include "pipeline/realtime/frame_slot.hpp"
#include "pipeline/run/run_outputs.hpp"
#include "slam/map_landmark.hpp"

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
  // Estimator thread, before frame `frame` is estimated: true with the correction to apply now
  // (Estimator::applyLoopCorrection: the move C_new_old and the covariance of the corrected
  // pose) when a solution is due (feedback on). With setWaitForBackEnd(true) it first waits for
  // the back end (see Determinism above). Then correctionApplied() with what moved.
  // `world_epoch`: the estimator's world (FrameSlot::world_epoch); a solution made for a
  // keyframe of another world (before a reset) is dropped, never applied.
  bool correctionBefore(std::int64_t frame, int world_epoch, Eigen::Isometry3d& C_new_old,
                        Eigen::Matrix<double, 6, 6>& cov_world);
  void correctionApplied(std::int64_t frame, const Eigen::Isometry3d& moved);
  void setWaitForBackEnd(bool wait);
  // Ends every wait of correctionBefore (a stage after the estimator failed; the run's end).
  void stopFeedback();
  // After the run: drains the back end, joins it, writes the optimised trajectory files and,
  // from `map` (the estimator's landmarks at the end; empty: none), landmarks_optimized.ply.
  Status finish(const std::vector<MapLandmark>& map);
  // After finish(): the world-frame correction M of a pose the estimator published at `frame`
  // (T_corrected = M T_online), as for landmarks_optimized.ply: the correction of the keyframe
  // at or before that frame, less the feedback moves applied after it up to the frame. False
  // when no loop was closed (nothing to correct).
  bool frameCorrection(std::int64_t frame, Eigen::Isometry3d& M) const;
  // Mapper thread, during the run: the number of solutions the back end has made so far, and a
  // function giving frameCorrection's answer for the newest of them (the moves the estimator
  // applied up to now included; a copy: safe while the back end goes on). False: no solution
  // yet.
  int solutionsMade() const;
  bool liveFrameCorrections(std::function<bool(std::int64_t, Eigen::Isometry3d&)>& out) const;
  // stats.json's "loop" object.
  std::string json() const;
  const run::StageTimes& times() const { return times_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  run::StageTimes times_;
};

}  // namespace svslam::rt
