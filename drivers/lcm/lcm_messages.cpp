// Conversions between the pipeline's reports and the svslam_lcm wire types (lcm_messages.hpp).
#include "drivers/lcm/lcm_messages.hpp"

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstring>
#include <exception>
#include <limits>

namespace svslam::drivers {
namespace {

constexpr const char* kCommandNames[] = {"reset", "save_map", "pause", "resume", "shutdown"};

bool finite(double v) { return std::isfinite(v); }

// Symmetric within a relative tolerance, finite, diagonal >= 0.
Status checkCovariance(const Eigen::Matrix<double, 6, 6>& P, const std::string& what) {
  if (!P.allFinite()) return Status::invalidArgument(what + ": covariance contains NaN or inf");
  const double tol = 1e-9 * std::max(1.0, P.cwiseAbs().maxCoeff());
  for (int i = 0; i < 6; ++i) {
    if (P(i, i) < 0.0)
      return Status::invalidArgument(what + ": covariance has a negative diagonal entry");
    for (int j = i + 1; j < 6; ++j)
      if (std::abs(P(i, j) - P(j, i)) > tol)
        return Status::invalidArgument(what + ": covariance is not symmetric (entry " +
                                       std::to_string(i) + "," + std::to_string(j) + ")");
  }
  return Status::ok();
}

// Big-endian walk over an encoded message: checks counts and string lengths against the
// remaining bytes before lcm-gen's decoder sizes its containers from them.
class WireWalker {
 public:
  WireWalker(const void* data, std::size_t size)
      : p_(static_cast<const std::uint8_t*>(data)), n_(size) {}
  bool skip(std::size_t k) {
    if (!ok_ || k > n_ - pos_) return ok_ = false;
    pos_ += k;
    return true;
  }
  // A count of elements of at least `min_elem_bytes` each that must fit in what is left.
  bool count(std::int32_t& v, std::size_t min_elem_bytes) {
    if (!readI32(v) || v < 0) return ok_ = false;
    if (static_cast<std::size_t>(v) * min_elem_bytes > n_ - pos_) return ok_ = false;
    return true;
  }
  bool str() {
    std::int32_t len = 0;
    if (!readI32(len) || len < 1 || static_cast<std::size_t>(len) > n_ - pos_) return ok_ = false;
    if (p_[pos_ + static_cast<std::size_t>(len) - 1] != 0) return ok_ = false;
    pos_ += static_cast<std::size_t>(len);
    return true;
  }
  bool strs(std::int32_t n) {
    for (std::int32_t i = 0; i < n && ok_; ++i) str();
    return ok_;
  }
  bool atEnd() const { return ok_ && pos_ == n_; }

 private:
  bool readI32(std::int32_t& v) {
    if (!ok_ || n_ - pos_ < 4) return ok_ = false;
    const std::uint32_t u = (std::uint32_t{p_[pos_]} << 24) | (std::uint32_t{p_[pos_ + 1]} << 16) |
                            (std::uint32_t{p_[pos_ + 2]} << 8) | std::uint32_t{p_[pos_ + 3]};
    std::memcpy(&v, &u, 4);
    pos_ += 4;
    return true;
  }
  const std::uint8_t* p_;
  std::size_t n_, pos_ = 0;
  bool ok_ = true;
};

bool scan(WireWalker& w, const svslam_lcm::pose_t*) {
  return w.skip(8 + 24) && w.str() && w.skip(24 + 32 + 288 + 1 + 4 + 8 + 8 + 4 + 1) && w.atEnd();
}
bool scan(WireWalker& w, const svslam_lcm::stats_t*) {
  std::int32_t ns = 0, nq = 0;
  std::int32_t nst = 0;
  return w.skip(8 + 40) && w.count(ns, 5) && w.strs(ns) && w.skip(24 * std::size_t(ns)) &&
         w.count(nq, 5) && w.strs(nq) && w.skip(16 * std::size_t(nq) + 24 + 48) && w.str() &&
         w.skip(8) && w.count(nst, 5) && w.strs(nst) && w.skip(16 * std::size_t(nst)) && w.atEnd();
}
bool scan(WireWalker& w, const svslam_lcm::map_summary_t*) {
  std::int32_t n = 0;
  return w.skip(8 + 16) && w.count(n, 12) && w.skip(12 * std::size_t(n)) && w.atEnd();
}
bool scan(WireWalker& w, const svslam_lcm::stereo_image_t*) {
  std::int32_t l = 0, r = 0;
  return w.skip(8 + 60) && w.count(l, 1) && w.skip(std::size_t(l)) && w.count(r, 1) &&
         w.skip(std::size_t(r)) && w.atEnd();
}
bool scan(WireWalker& w, const svslam_lcm::command_t*) {
  return w.skip(8 + 16) && w.str() && w.str() && w.str() && w.atEnd();
}
bool scan(WireWalker& w, const svslam_lcm::command_status_t*) {
  return w.skip(8 + 16) && w.str() && w.skip(1) && w.str() && w.atEnd();
}
bool scan(WireWalker& w, const svslam_lcm::altitude_t*) { return w.skip(8 + 24) && w.atEnd(); }

template <class Msg>
Status decodeChecked(const void* data, std::size_t size, Msg& out, const char* type) {
  const std::string what = std::string("svslam_lcm.") + type;
  if (data == nullptr || size < 8 || size > static_cast<std::size_t>(INT_MAX))
    return Status::corruptData(what + ": " + std::to_string(size) + " bytes is not a message");
  std::int64_t hash = 0;
  if (__int64_t_decode_array(data, 0, 8, &hash, 1) != 8 || hash != Msg::getHash())
    return Status::corruptData(what + ": type hash mismatch (another type or garbage)");
  WireWalker w(data, size);
  if (!scan(w, static_cast<const Msg*>(nullptr)))
    return Status::corruptData(what + ": truncated or inconsistent lengths");
  try {
    if (out.decode(data, 0, static_cast<int>(size)) != static_cast<int>(size))
      return Status::corruptData(what + ": decode failed");
  } catch (const std::exception& e) {
    return Status::corruptData(what + ": decode failed (" + e.what() + ")");
  }
  return Status::ok();
}

}  // namespace

const char* commandName(CommandKind kind) { return kCommandNames[static_cast<int>(kind)]; }

Result<CommandKind> parseCommandKind(const std::string& name) {
  for (int i = 0; i < 5; ++i)
    if (name == kCommandNames[i]) return static_cast<CommandKind>(i);
  return Status::invalidArgument("unknown command '" + name +
                                 "' (use reset, save_map, pause, resume or shutdown)");
}

std::int64_t toUtime(TimeNs t_ns) { return t_ns / kNsPerUs; }

Result<TimeNs> fromUtime(std::int64_t utime) {
  constexpr std::int64_t kMax = std::numeric_limits<std::int64_t>::max() / kNsPerUs;
  if (utime > kMax || utime < -kMax)
    return Status::invalidArgument("utime " + std::to_string(utime) + " us overflows int64 ns");
  return utime * kNsPerUs;
}

namespace {
// The health fields of a pose: counts >= 0, statistics finite and >= 0.
Status checkHealth(const PoseReport& r, const std::string& what) {
  if (r.motion_inliers < 0 || r.landmarks_observed < 0)
    return Status::invalidArgument(what + ": negative inlier or landmark count");
  if (!(std::isfinite(r.motion_residual_per_dof) && r.motion_residual_per_dof >= 0.0) ||
      !(std::isfinite(r.observation_nis_per_dof) && r.observation_nis_per_dof >= 0.0))
    return Status::invalidArgument(what + ": health statistics must be finite and >= 0");
  return Status::ok();
}
}  // namespace

Result<svslam_lcm::pose_t> toLcm(const PoseReport& r) {
  const Eigen::Matrix3d R = r.T_world_cam.linear();
  const Eigen::Vector3d p = r.T_world_cam.translation();
  if (!R.allFinite() || !p.allFinite())
    return Status::invalidArgument("pose " + std::to_string(r.seq) + ": NaN or inf in pose");
  if ((R.transpose() * R - Eigen::Matrix3d::Identity()).norm() > 1e-6 || R.determinant() < 0.0)
    return Status::invalidArgument("pose " + std::to_string(r.seq) + ": rotation not orthonormal");
  if (Status s = checkCovariance(r.cov, "pose " + std::to_string(r.seq)); !s) return s;
  if (r.frame_id.empty()) return Status::invalidArgument("pose: empty frame_id");
  svslam_lcm::pose_t m;
  m.utime = toUtime(r.t_ns);
  m.publish_utime = toUtime(r.publish_t_ns);
  m.seq = r.seq;
  m.frame_id = r.frame_id;
  const Eigen::Quaterniond q(R);
  for (int i = 0; i < 3; ++i) m.position[i] = p[i];
  m.orientation[0] = q.w();
  m.orientation[1] = q.x();
  m.orientation[2] = q.y();
  m.orientation[3] = q.z();
  for (int k = 0; k < 36; ++k) m.covariance[k] = r.cov(k / 6, k % 6);
  m.status = static_cast<std::int8_t>(r.status);
  if (Status s = checkHealth(r, "pose " + std::to_string(r.seq)); !s) return s;
  m.motion_inliers = r.motion_inliers;
  m.motion_residual_per_dof = r.motion_residual_per_dof;
  m.observation_nis_per_dof = r.observation_nis_per_dof;
  m.landmarks_observed = r.landmarks_observed;
  m.search = static_cast<std::int8_t>(r.search);
  return m;
}

Result<PoseReport> fromLcm(const svslam_lcm::pose_t& m) {
  const std::string what = "pose_t seq " + std::to_string(m.seq);
  PoseReport r;
  auto t = fromUtime(m.utime);
  auto tp = fromUtime(m.publish_utime);
  if (!t) return t.status();
  if (!tp) return tp.status();
  r.t_ns = *t;
  r.publish_t_ns = *tp;
  r.seq = m.seq;
  if (m.frame_id.empty()) return Status::invalidArgument(what + ": empty frame_id");
  r.frame_id = m.frame_id;
  Eigen::Vector3d p(m.position[0], m.position[1], m.position[2]);
  Eigen::Quaterniond q(m.orientation[0], m.orientation[1], m.orientation[2], m.orientation[3]);
  if (!p.allFinite() || !q.coeffs().allFinite())
    return Status::invalidArgument(what + ": NaN or inf in pose");
  if (std::abs(q.norm() - 1.0) > 1e-3)
    return Status::invalidArgument(what + ": orientation is not a unit quaternion");
  r.T_world_cam = Eigen::Isometry3d::Identity();
  r.T_world_cam.linear() = q.normalized().toRotationMatrix();
  r.T_world_cam.translation() = p;
  for (int k = 0; k < 36; ++k) r.cov(k / 6, k % 6) = m.covariance[k];
  if (Status s = checkCovariance(r.cov, what); !s) return s;
  if (m.status < 0 || m.status > 3)
    return Status::invalidArgument(what + ": unknown status " + std::to_string(m.status));
  r.status = static_cast<TrackingStatus>(m.status);
  if (m.search < 0 || m.search > 2)
    return Status::invalidArgument(what + ": unknown search " + std::to_string(m.search));
  r.motion_inliers = m.motion_inliers;
  r.motion_residual_per_dof = m.motion_residual_per_dof;
  r.observation_nis_per_dof = m.observation_nis_per_dof;
  r.landmarks_observed = m.landmarks_observed;
  r.search = static_cast<SearchKind>(m.search);
  if (Status s = checkHealth(r, what); !s) return s;
  return r;
}

Result<svslam_lcm::stats_t> toLcm(const StatsReport& r) {
  if (r.frames_in < 0 || r.frames_out < 0 || r.frames_dropped < 0 || r.frames_tracked < 0)
    return Status::invalidArgument("stats: negative frame count");
  if (!finite(r.e2e_p50_ms) || !finite(r.e2e_p99_ms) || !finite(r.e2e_max_ms))
    return Status::invalidArgument("stats: end-to-end latency is NaN or inf");
  svslam_lcm::stats_t m;
  m.utime = toUtime(r.t_ns);
  m.frames_in = r.frames_in;
  m.frames_out = r.frames_out;
  m.frames_dropped = r.frames_dropped;
  m.frames_tracked = r.frames_tracked;
  for (const auto& s : r.stages) {
    if (s.name.empty()) return Status::invalidArgument("stats: stage without a name");
    if (!finite(s.p50_ms) || !finite(s.p99_ms) || !finite(s.max_ms))
      return Status::invalidArgument("stats: latency of stage '" + s.name + "' is NaN or inf");
    m.stage_name.push_back(s.name);
    m.p50_ms.push_back(s.p50_ms);
    m.p99_ms.push_back(s.p99_ms);
    m.max_ms.push_back(s.max_ms);
  }
  for (const auto& q : r.queues) {
    if (q.name.empty()) return Status::invalidArgument("stats: queue without a name");
    if (q.depth < 0 || q.capacity < 0 || q.drops < 0)
      return Status::invalidArgument("stats: negative count in queue '" + q.name + "'");
    m.queue_name.push_back(q.name);
    m.queue_depth.push_back(q.depth);
    m.queue_capacity.push_back(q.capacity);
    m.queue_drops.push_back(q.drops);
  }
  m.num_stages = static_cast<std::int32_t>(r.stages.size());
  m.num_queues = static_cast<std::int32_t>(r.queues.size());
  m.e2e_p50_ms = r.e2e_p50_ms;
  m.e2e_p99_ms = r.e2e_p99_ms;
  m.e2e_max_ms = r.e2e_max_ms;
  const CommandCounts& cc = r.commands;
  if (cc.accepted < 0 ||
      std::any_of(cc.refused.begin(), cc.refused.end(), [](std::int64_t n) { return n < 0; }))
    return Status::invalidArgument("stats: negative command count");
  m.commands_accepted = cc.accepted;
  m.commands_refused_disabled = cc.refusedBy(CommandRefusal::kDisabled);
  m.commands_refused_no_token = cc.refusedBy(CommandRefusal::kNoToken);
  m.commands_refused_bad_token = cc.refusedBy(CommandRefusal::kBadToken);
  m.commands_refused_rate_limited = cc.refusedBy(CommandRefusal::kRateLimited);
  m.commands_malformed = cc.refusedBy(CommandRefusal::kMalformed);
  if (!finite(r.stalled_ms) || r.stalled_ms < 0)
    return Status::invalidArgument("stats: stalled_ms is negative, NaN or inf");
  if (r.stalled_stage.empty() != (r.stalled_ms == 0))
    return Status::invalidArgument("stats: a stalled stage needs stalled_ms > 0, and only it");
  m.stalled_stage = r.stalled_stage;
  m.stalled_ms = r.stalled_ms;
  for (const StallReport& st : r.stalls) {
    if (st.stage.empty()) return Status::invalidArgument("stats: stall without a stage name");
    if (st.count < 1 || !finite(st.longest_ms) || st.longest_ms < 0)
      return Status::invalidArgument("stats: stall count or duration of stage '" + st.stage +
                                     "' invalid");
    m.stall_stage.push_back(st.stage);
    m.stall_count.push_back(st.count);
    m.stall_longest_ms.push_back(st.longest_ms);
  }
  m.num_stalls = static_cast<std::int32_t>(r.stalls.size());
  return m;
}

Result<StatsReport> fromLcm(const svslam_lcm::stats_t& m) {
  const auto ns = static_cast<std::size_t>(std::max(m.num_stages, 0));
  const auto nq = static_cast<std::size_t>(std::max(m.num_queues, 0));
  if (m.num_stages < 0 || m.stage_name.size() != ns || m.p50_ms.size() != ns ||
      m.p99_ms.size() != ns || m.max_ms.size() != ns || m.num_queues < 0 ||
      m.queue_name.size() != nq || m.queue_depth.size() != nq || m.queue_capacity.size() != nq ||
      m.queue_drops.size() != nq || m.num_stalls < 0 ||
      m.stall_stage.size() != static_cast<std::size_t>(m.num_stalls) ||
      m.stall_count.size() != m.stall_stage.size() ||
      m.stall_longest_ms.size() != m.stall_stage.size())
    return Status::invalidArgument(
        "stats_t: array sizes differ from num_stages / num_queues / num_stalls");
  StatsReport r;
  auto t = fromUtime(m.utime);
  if (!t) return t.status();
  r.t_ns = *t;
  r.frames_in = m.frames_in;
  r.frames_out = m.frames_out;
  r.frames_dropped = m.frames_dropped;
  r.frames_tracked = m.frames_tracked;
  for (std::size_t i = 0; i < ns; ++i)
    r.stages.push_back({m.stage_name[i], m.p50_ms[i], m.p99_ms[i], m.max_ms[i]});
  for (std::size_t i = 0; i < nq; ++i)
    r.queues.push_back({m.queue_name[i], m.queue_depth[i], m.queue_capacity[i], m.queue_drops[i]});
  r.e2e_p50_ms = m.e2e_p50_ms;
  r.e2e_p99_ms = m.e2e_p99_ms;
  r.e2e_max_ms = m.e2e_max_ms;
  r.commands.accepted = m.commands_accepted;
  auto set = [&](CommandRefusal k, std::int64_t n) { r.commands.refused[static_cast<int>(k)] = n; };
  set(CommandRefusal::kDisabled, m.commands_refused_disabled);
  set(CommandRefusal::kNoToken, m.commands_refused_no_token);
  set(CommandRefusal::kBadToken, m.commands_refused_bad_token);
  set(CommandRefusal::kRateLimited, m.commands_refused_rate_limited);
  set(CommandRefusal::kMalformed, m.commands_malformed);
  r.stalled_stage = m.stalled_stage;
  r.stalled_ms = m.stalled_ms;
  for (std::size_t i = 0; i < m.stall_stage.size(); ++i)
    r.stalls.push_back({m.stall_stage[i], m.stall_count[i], m.stall_longest_ms[i]});
  // Same checks as on the way out.
  if (auto back = toLcm(r); !back) return back.status();
  return r;
}

Result<svslam_lcm::map_summary_t> toLcm(const MapSummaryReport& r) {
  if (r.landmarks_in_state < 0 || r.landmarks_in_map < 0)
    return Status::invalidArgument("map summary: negative landmark count");
  if (r.points_world.size() > static_cast<std::size_t>(INT32_MAX / 12))
    return Status::invalidArgument("map summary: too many points");
  svslam_lcm::map_summary_t m;
  m.utime = toUtime(r.t_ns);
  m.landmarks_in_state = r.landmarks_in_state;
  m.landmarks_in_map = r.landmarks_in_map;
  m.num_points = static_cast<std::int32_t>(r.points_world.size());
  m.xyz.reserve(r.points_world.size());
  for (const auto& p : r.points_world) {
    if (!p.allFinite()) return Status::invalidArgument("map summary: point is NaN or inf");
    m.xyz.push_back({p.x(), p.y(), p.z()});
  }
  return m;
}

Result<MapSummaryReport> fromLcm(const svslam_lcm::map_summary_t& m) {
  if (m.num_points < 0 || m.xyz.size() != static_cast<std::size_t>(m.num_points))
    return Status::invalidArgument("map_summary_t: xyz size differs from num_points");
  MapSummaryReport r;
  auto t = fromUtime(m.utime);
  if (!t) return t.status();
  r.t_ns = *t;
  r.landmarks_in_state = m.landmarks_in_state;
  r.landmarks_in_map = m.landmarks_in_map;
  for (const auto& p : m.xyz) {
    if (p.size() != 3) return Status::invalidArgument("map_summary_t: point without 3 values");
    r.points_world.emplace_back(p[0], p[1], p[2]);
  }
  if (auto back = toLcm(r); !back) return back.status();
  return r;
}

Result<svslam_lcm::command_t> toLcm(const Command& c) {
  const int k = static_cast<int>(c.kind);
  if (k < 0 || k > 4) return Status::invalidArgument("command: unknown kind " + std::to_string(k));
  svslam_lcm::command_t m;
  m.utime = toUtime(c.t_ns);
  m.seq = c.seq;
  m.command = commandName(c.kind);
  m.argument = c.argument;
  m.token = c.token;
  return m;
}

Result<Command> fromLcm(const svslam_lcm::command_t& m) {
  auto kind = parseCommandKind(m.command);
  if (!kind) return kind.status();
  auto t = fromUtime(m.utime);
  if (!t) return t.status();
  Command c;
  c.t_ns = *t;
  c.seq = m.seq;
  c.kind = *kind;
  c.argument = m.argument;
  c.token = m.token;
  return c;
}

Result<svslam_lcm::command_status_t> toLcm(const CommandStatus& s) {
  if (s.command.empty()) return Status::invalidArgument("command status: empty command");
  svslam_lcm::command_status_t m;
  m.utime = toUtime(s.t_ns);
  m.seq = s.seq;
  m.command = s.command;
  m.ok = s.ok;
  m.message = s.message;
  return m;
}

Result<CommandStatus> fromLcm(const svslam_lcm::command_status_t& m) {
  auto t = fromUtime(m.utime);
  if (!t) return t.status();
  if (m.command.empty()) return Status::invalidArgument("command_status_t: empty command");
  return CommandStatus{*t, m.seq, m.command, m.ok != 0, m.message};
}

Status decodeLcm(const void* d, std::size_t n, svslam_lcm::pose_t& out) {
  return decodeChecked(d, n, out, "pose_t");
}
Status decodeLcm(const void* d, std::size_t n, svslam_lcm::stats_t& out) {
  return decodeChecked(d, n, out, "stats_t");
}
Status decodeLcm(const void* d, std::size_t n, svslam_lcm::map_summary_t& out) {
  return decodeChecked(d, n, out, "map_summary_t");
}
Status decodeLcm(const void* d, std::size_t n, svslam_lcm::stereo_image_t& out) {
  return decodeChecked(d, n, out, "stereo_image_t");
}
Status decodeLcm(const void* d, std::size_t n, svslam_lcm::command_t& out) {
  return decodeChecked(d, n, out, "command_t");
}
Status decodeLcm(const void* d, std::size_t n, svslam_lcm::command_status_t& out) {
  return decodeChecked(d, n, out, "command_status_t");
}

Status decodeLcm(const void* d, std::size_t n, svslam_lcm::altitude_t& out) {
  return decodeChecked(d, n, out, "altitude_t");
}

}  // namespace svslam::drivers
