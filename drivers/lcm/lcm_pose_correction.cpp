// pose_correction_t <-> PoseCorrectionMessage (lcm_pose_correction.hpp).
#include "drivers/lcm/lcm_pose_correction.hpp"

#include <cmath>
#include <cstring>
#include <exception>
#include <limits>

#include "svslam_lcm/pose_correction_t.hpp"

namespace svslam::drivers {
namespace {

constexpr const char* kWhat = "svslam_lcm.pose_correction_t";
constexpr std::size_t kPerKeyframeBytes = 8 + 3 * 8 + 4 * 8;

std::int32_t readI32(const std::uint8_t* p) {
  const std::uint32_t u = (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) |
                          (std::uint32_t{p[2]} << 8) | std::uint32_t{p[3]};
  return static_cast<std::int32_t>(u);
}

Status corrupt(const std::string& m) { return Status::corruptData(std::string(kWhat) + ": " + m); }

// A time in microseconds that converts to int64 nanoseconds without overflow.
bool utimeFits(std::int64_t us) {
  constexpr std::int64_t kMax = std::numeric_limits<std::int64_t>::max() / 1000;
  return us >= -kMax && us <= kMax;
}

bool rigid(const Eigen::Isometry3d& T) {
  if (!T.matrix().allFinite()) return false;
  const Eigen::Matrix3d E = T.linear().transpose() * T.linear() - Eigen::Matrix3d::Identity();
  return E.cwiseAbs().maxCoeff() < 1e-6;
}

}  // namespace

Status encodePoseCorrection(const PoseCorrectionMessage& m, std::vector<std::uint8_t>& out) {
  const std::size_t n = m.keyframe_t_ns.size();
  if (n != m.correction.size())
    return Status::invalidArgument("pose correction: keyframe times and corrections differ in count");
  if (n > static_cast<std::size_t>(kMaxCorrectionKeyframesPerPart))
    return Status::invalidArgument("pose correction: more than " +
                                   std::to_string(kMaxCorrectionKeyframesPerPart) +
                                   " keyframes in one part");
  if (m.parts < 1 || m.part < 0 || m.part >= m.parts)
    return Status::invalidArgument("pose correction: part must be in 0 .. parts - 1");
  svslam_lcm::pose_correction_t w;
  w.utime = m.t_ns / 1000;
  w.correction_seq = m.correction_seq;
  w.part = m.part;
  w.parts = m.parts;
  w.frame_id = m.frame_id;
  w.loops_accepted = m.loops_accepted;
  w.keyframes_total = m.keyframes_total;
  w.num_keyframes = static_cast<std::int32_t>(n);
  w.keyframe_utime.resize(n);
  w.position.assign(n, std::vector<double>(3));
  w.orientation.assign(n, std::vector<double>(4));
  for (std::size_t k = 0; k < n; ++k) {
    if (!rigid(m.correction[k]))
      return Status::invalidArgument("pose correction: keyframe " + std::to_string(k) +
                                     " has a non-finite or non-rigid correction");
    if (k > 0 && m.keyframe_t_ns[k] <= m.keyframe_t_ns[k - 1])
      return Status::invalidArgument("pose correction: keyframe times must increase");
    w.keyframe_utime[k] = m.keyframe_t_ns[k] / 1000;
    const Eigen::Vector3d t = m.correction[k].translation();
    const Eigen::Quaterniond q(m.correction[k].linear());
    for (int i = 0; i < 3; ++i) w.position[k][static_cast<std::size_t>(i)] = t[i];
    w.orientation[k][0] = q.w();
    w.orientation[k][1] = q.x();
    w.orientation[k][2] = q.y();
    w.orientation[k][3] = q.z();
  }
  const int len = w.getEncodedSize();
  out.resize(static_cast<std::size_t>(len));
  if (w.encode(out.data(), 0, len) != len) return Status::ioError("pose correction: encode failed");
  return Status::ok();
}

Status decodePoseCorrection(const std::uint8_t* data, std::size_t size, PoseCorrectionMessage& out) {
  // hash 8, utime 8, correction_seq 8, part 4, parts 4, frame_id (4 + len), loops 4, total 4, n 4
  if (data == nullptr || size < 8 + 8 + 8 + 4 + 4 + 4) return corrupt("message too short");
  const std::int32_t str_len = readI32(data + 32);
  if (str_len < 1 || static_cast<std::size_t>(str_len) > size)
    return corrupt("frame_id length out of range");
  const std::size_t n_at = 36 + static_cast<std::size_t>(str_len) + 8;
  if (size < n_at + 4) return corrupt("message too short");
  const std::int32_t n = readI32(data + n_at);
  if (n < 0 || n > kMaxCorrectionKeyframesPerPart)
    return corrupt("num_keyframes out of range: " + std::to_string(n));
  if (size != n_at + 4 + static_cast<std::size_t>(n) * kPerKeyframeBytes)
    return corrupt("size " + std::to_string(size) + " is not what its header implies");
  svslam_lcm::pose_correction_t w;
  try {
    if (w.decode(data, 0, static_cast<int>(size)) != static_cast<int>(size))
      return corrupt("cannot decode (wrong type hash or layout)");
  } catch (const std::exception& e) {
    return corrupt(std::string("cannot decode: ") + e.what());
  }
  if (w.parts < 1 || w.part < 0 || w.part >= w.parts) return corrupt("part out of range");
  if (!utimeFits(w.utime)) return corrupt("utime out of range");
  PoseCorrectionMessage m;
  m.t_ns = w.utime * 1000;
  m.correction_seq = w.correction_seq;
  m.part = w.part;
  m.parts = w.parts;
  m.frame_id = w.frame_id;
  m.loops_accepted = w.loops_accepted;
  m.keyframes_total = w.keyframes_total;
  for (std::int32_t k = 0; k < w.num_keyframes; ++k) {
    const auto& p = w.position[static_cast<std::size_t>(k)];
    const auto& o = w.orientation[static_cast<std::size_t>(k)];
    if (p.size() != 3 || o.size() != 4) return corrupt("malformed keyframe arrays");
    const Eigen::Quaterniond q(o[0], o[1], o[2], o[3]);
    const Eigen::Vector3d t(p[0], p[1], p[2]);
    if (!utimeFits(w.keyframe_utime[static_cast<std::size_t>(k)]))
      return corrupt("keyframe " + std::to_string(k) + ": keyframe_utime out of range");
    if (!t.allFinite() || !q.coeffs().allFinite() || std::abs(q.norm() - 1.0) > 1e-6)
      return corrupt("keyframe " + std::to_string(k) + ": non-finite value or non-unit quaternion");
    Eigen::Isometry3d C = Eigen::Isometry3d::Identity();
    C.linear() = q.toRotationMatrix();
    C.translation() = t;
    m.keyframe_t_ns.push_back(w.keyframe_utime[static_cast<std::size_t>(k)] * 1000);
    m.correction.push_back(C);
  }
  out = std::move(m);
  return Status::ok();
}

std::vector<PoseCorrectionMessage> splitPoseCorrection(const PoseCorrectionMessage& whole) {
  std::vector<PoseCorrectionMessage> parts;
  const std::size_t n = whole.keyframe_t_ns.size();
  const std::size_t per = static_cast<std::size_t>(kMaxCorrectionKeyframesPerPart);
  const std::size_t count = n == 0 ? 1 : (n + per - 1) / per;
  for (std::size_t p = 0; p < count; ++p) {
    PoseCorrectionMessage m = whole;
    m.part = static_cast<int>(p);
    m.parts = static_cast<int>(count);
    const std::size_t a = p * per, b = std::min(n, a + per);
    m.keyframe_t_ns.assign(whole.keyframe_t_ns.begin() + static_cast<std::ptrdiff_t>(a),
                           whole.keyframe_t_ns.begin() + static_cast<std::ptrdiff_t>(b));
    m.correction.assign(whole.correction.begin() + static_cast<std::ptrdiff_t>(a),
                        whole.correction.begin() + static_cast<std::ptrdiff_t>(b));
    parts.push_back(std::move(m));
  }
  return parts;
}

}  // namespace svslam::drivers
