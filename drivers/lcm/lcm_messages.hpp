#pragma once
// Plain C++ reports of the pipeline and their LCM wire form (package svslam_lcm, lcm/*.lcm).
//
// Conversions are pure functions that validate their input: nothing non-finite is ever
// published, and messages received from the network are checked before use.
//
// Conventions on the wire:
//   - utime: int64 microseconds (TimeNs / 1000, truncated toward zero); t_ns = utime * 1000.
//   - pose: T_world_cam of the left camera; position in metres, orientation (w, x, y, z).
//   - covariance: 6x6 row-major, order [rot_x rot_y rot_z (rad), trans_x trans_y trans_z (m)],
//     error right-multiplied: T_true = T_est * exp(dxi), dxi = [dtheta; drho] (camera frame).
//   - stereo_image_t: rectified 8-bit grey pair, rows `stride` bytes apart.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/camera.hpp"
#include "core/status.hpp"
#include "core/time.hpp"
#include "drivers/lcm/command_gate.hpp"
#include "drivers/source/stereo_source.hpp"
#include "svslam_lcm/altitude_t.hpp"
#include "svslam_lcm/command_status_t.hpp"
#include "svslam_lcm/command_t.hpp"
#include "svslam_lcm/map_summary_t.hpp"
#include "svslam_lcm/pose_t.hpp"
#include "svslam_lcm/stats_t.hpp"
#include "svslam_lcm/stereo_image_t.hpp"

namespace svslam::drivers {

// Same values as svslam_lcm::pose_t::TRACKING / LOST / INITIALIZING / MONOCULAR.
enum class TrackingStatus : int {
  kTracking = 0,      // pose measured from the current frame
  kLost = 1,          // motion predicted, not measured
  kInitializing = 2,  // no map yet
  kMonocular = 3,     // right camera unusable: bearings of the map, left image only
};

enum class SearchKind : std::int8_t { kPredicted = 0, kRepredicted = 1, kRetried = 2 };

struct PoseReport {
  TimeNs t_ns = 0;          // capture time of the frame
  TimeNs publish_t_ns = 0;  // time of publication (same clock as t_ns when live)
  std::int64_t seq = 0;     // frame sequence number
  std::string frame_id = "svslam_world";
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();  // left camera, metres
  // 6x6 covariance [rot (rad), trans (m)], right-multiplied error (see top of file).
  Eigen::Matrix<double, 6, 6> cov = Eigen::Matrix<double, 6, 6>::Zero();
  TrackingStatus status = TrackingStatus::kTracking;
  // Health (lcm/pose_t.lcm): finite and >= 0.
  int motion_inliers = 0;
  double motion_residual_per_dof = 0.0;
  double observation_nis_per_dof = 0.0;
  int landmarks_observed = 0;
  SearchKind search = SearchKind::kPredicted;
};

struct StageLatency {
  std::string name;
  double p50_ms = 0, p99_ms = 0, max_ms = 0;  // processing time per frame, milliseconds
};

struct QueueReport {
  std::string name;
  int depth = 0, capacity = 0;  // items
  std::int64_t drops = 0;       // items dropped since start
};

// A stage that stalled: worked on one frame for longer than the stall timeout.
struct StallReport {
  std::string stage;
  std::int64_t count = 0;  // stalls since start
  double longest_ms = 0;   // the longest, ms
};

struct StatsReport {
  TimeNs t_ns = 0;  // time of the report
  std::int64_t frames_in = 0, frames_out = 0, frames_dropped = 0, frames_tracked = 0;
  std::vector<StageLatency> stages;
  std::vector<QueueReport> queues;
  double e2e_p50_ms = 0, e2e_p99_ms = 0, e2e_max_ms = 0;  // capture -> publish, milliseconds
  CommandCounts commands;  // commands received since start: accepted, refused by reason
  std::string stalled_stage;        // the stage stalled at the time of the report; "" = none
  double stalled_ms = 0;            // how long it has been working on its frame, ms
  std::vector<StallReport> stalls;  // the stages that stalled since start
};

struct MapSummaryReport {
  TimeNs t_ns = 0;
  int landmarks_in_state = 0, landmarks_in_map = 0;
  std::vector<Eigen::Vector3f> points_world;  // active landmarks, world frame, metres
};

enum class CommandKind { kReset, kSaveMap, kPause, kResume, kShutdown };

struct Command {
  TimeNs t_ns = 0;
  std::int64_t seq = 0;
  CommandKind kind = CommandKind::kReset;
  std::string argument;  // e.g. the file of save_map; may be empty
  std::string token;     // shared secret of the service (CommandGate); empty = none
};

struct CommandStatus {
  TimeNs t_ns = 0;
  std::int64_t seq = 0;  // seq of the command answered
  std::string command;   // command name as received
  bool ok = true;
  std::string message;
};

// "reset", "save_map", "pause", "resume", "shutdown".
const char* commandName(CommandKind kind);
// Error naming the unknown string and listing the valid ones.
Result<CommandKind> parseCommandKind(const std::string& name);

// Microseconds <-> nanoseconds; fromUtime fails when utime * 1000 overflows int64.
std::int64_t toUtime(TimeNs t_ns);
Result<TimeNs> fromUtime(std::int64_t utime);

// Reports -> wire. Errors: non-finite values (pose, covariance, latencies, points), a
// non-orthonormal rotation, a non-symmetric or negative-diagonal covariance, negative counts,
// an empty frame_id or stage/queue name.
Result<svslam_lcm::pose_t> toLcm(const PoseReport& r);
Result<svslam_lcm::stats_t> toLcm(const StatsReport& r);
Result<svslam_lcm::map_summary_t> toLcm(const MapSummaryReport& r);
Result<svslam_lcm::command_t> toLcm(const Command& c);
Result<svslam_lcm::command_status_t> toLcm(const CommandStatus& s);

// Wire -> reports, with the same checks (a quaternion must have unit norm within 1e-3; it is
// renormalised). Inconsistent array counts are errors.
Result<PoseReport> fromLcm(const svslam_lcm::pose_t& m);
Result<StatsReport> fromLcm(const svslam_lcm::stats_t& m);
Result<MapSummaryReport> fromLcm(const svslam_lcm::map_summary_t& m);
Result<Command> fromLcm(const svslam_lcm::command_t& m);  // unknown command -> error naming it
Result<CommandStatus> fromLcm(const svslam_lcm::command_status_t& m);

// Checks a received stereo image: width, height in [1, 16384]; stride >= width;
// left_size == right_size == stride * height == size of each byte array; f_px and baseline_m
// finite and > 0; cx_px in [0, width), cy_px in [0, height).
Status validateStereoImage(const svslam_lcm::stereo_image_t& m);
// Calibration of a valid stereo image (validateStereoImage first).
Result<StereoCalibration> calibrationOf(const svslam_lcm::stereo_image_t& m);
// Copies the pair into `out` (buffers reused; t_ns from utime; index untouched).
Status toStereoFrame(const svslam_lcm::stereo_image_t& m, StereoFrame& out);
// Packs a rectified pair (same size as calib) into a message (stride = width).
Result<svslam_lcm::stereo_image_t> toLcmStereoImage(const ImageU8& left, const ImageU8& right,
                                                    const StereoCalibration& calib, TimeNs t_ns,
                                                    std::int64_t seq);

// Encoding into `buf` (resized). Never fails for messages produced by toLcm.
template <class Msg>
Status encodeLcm(const Msg& m, std::vector<std::uint8_t>& buf) {
  const int n = m.getEncodedSize();
  if (n < 0) return Status::invalidArgument("LCM message too large to encode");
  buf.resize(static_cast<std::size_t>(n));
  if (m.encode(buf.data(), 0, n) != n) return Status::invalidArgument("LCM encode failed");
  return Status::ok();
}

// Safe decoding of untrusted bytes: the array counts and string lengths are checked against
// the buffer before lcm-gen's decoder allocates anything, the type hash must match and the
// whole buffer must be consumed. Errors are kCorruptData naming the type.
Status decodeLcm(const void* data, std::size_t size, svslam_lcm::pose_t& out);
Status decodeLcm(const void* data, std::size_t size, svslam_lcm::stats_t& out);
Status decodeLcm(const void* data, std::size_t size, svslam_lcm::map_summary_t& out);
Status decodeLcm(const void* data, std::size_t size, svslam_lcm::stereo_image_t& out);
Status decodeLcm(const void* data, std::size_t size, svslam_lcm::command_t& out);
Status decodeLcm(const void* data, std::size_t size, svslam_lcm::command_status_t& out);
Status decodeLcm(const void* data, std::size_t size, svslam_lcm::altitude_t& out);

}  // namespace svslam::drivers
