#pragma once
// A loop-closure correction on the wire (svslam_lcm.pose_correction_t,
// lcm/pose_correction_t.lcm): per keyframe, the world-frame transform C_k that moves poses
// already published into the corrected frame (T_corrected = C_k T_world_cam).
#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/status.hpp"
#include "core/time.hpp"

namespace svslam::drivers {

inline constexpr int kMaxCorrectionKeyframesPerPart = 4096;

struct PoseCorrectionMessage {
  TimeNs t_ns = 0;  // capture time of the keyframe that accepted the loops (utime on the wire)
  std::int64_t correction_seq = 0;
  int part = 0, parts = 1;
  std::string frame_id = "svslam_world";
  int loops_accepted = 0;
  int keyframes_total = 0;
  std::vector<TimeNs> keyframe_t_ns;         // increasing (microsecond resolution on the wire)
  std::vector<Eigen::Isometry3d> correction;  // C_k, one per keyframe_t_ns
};

// Encodes `m` (at most kMaxCorrectionKeyframesPerPart keyframes, finite rigid transforms,
// 0 <= part < parts, increasing times). Errors name the problem.
Status encodePoseCorrection(const PoseCorrectionMessage& m, std::vector<std::uint8_t>& out);

// Decodes untrusted bytes: kCorruptData on a wrong type hash, a size other than the header
// implies, a keyframe count out of range, a non-finite value or a quaternion whose norm is not
// 1 (to 1e-6). `out` is untouched on error.
Status decodePoseCorrection(const std::uint8_t* data, std::size_t size, PoseCorrectionMessage& out);

// Splits corrections of many keyframes into parts of at most kMaxCorrectionKeyframesPerPart.
std::vector<PoseCorrectionMessage> splitPoseCorrection(const PoseCorrectionMessage& whole);

}  // namespace svslam::drivers
