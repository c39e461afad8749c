#include "pipeline/cli/listen_lines.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <vector>

#include "drivers/lcm/lcm_map_tile.hpp"
#include "drivers/lcm/lcm_messages.hpp"
#include "drivers/lcm/lcm_pose_correction.hpp"
#include "pipeline/cli/json_writer.hpp"
#include "svslam_lcm/map_tile_t.hpp"
#include "svslam_lcm/pose_correction_t.hpp"

namespace svslam::cli {
namespace {

std::string jsonArray(const double* v, std::size_t n, const char* fmt) {
  std::string s = "[";
  char buf[64];
  for (std::size_t i = 0; i < n; ++i) {
    if (std::isfinite(v[i])) {
      std::snprintf(buf, sizeof buf, fmt, v[i]);
    } else {
      std::snprintf(buf, sizeof buf, "null");
    }
    s += (i ? ", " : "") + std::string(buf);
  }
  return s + "]";
}

const char* statusName(drivers::TrackingStatus s) {
  switch (s) {
    case drivers::TrackingStatus::kTracking:
      return "tracking";
    case drivers::TrackingStatus::kLost:
      return "lost";
    case drivers::TrackingStatus::kInitializing:
      return "initializing";
    case drivers::TrackingStatus::kMonocular:
      return "monocular";
  }
  return "unknown";
}

const char* searchName(drivers::SearchKind s) {
  switch (s) {
    case drivers::SearchKind::kPredicted:
      return "predicted";
    case drivers::SearchKind::kRepredicted:
      return "repredicted";
    case drivers::SearchKind::kRetried:
      return "retried";
  }
  return "unknown";
}

JsonObject header(ListenType t, const std::string& channel) {
  JsonObject j;
  j.add("type", listenTypeName(t)).add("channel", channel);
  return j;
}

ListenLine failed(ListenType t, const Status& s) { return {t, "", s.message()}; }
ListenLine done(ListenType t, const JsonObject& j) { return {t, j.str(), ""}; }

ListenLine poseLine(const std::string& channel, const std::uint8_t* d, std::size_t n) {
  svslam_lcm::pose_t m;
  Status s = drivers::decodeLcm(d, n, m);
  Result<drivers::PoseReport> r = s ? drivers::fromLcm(m) : Result<drivers::PoseReport>(s);
  if (!r) return failed(ListenType::kPose, r.status());
  double diag[6];
  for (int i = 0; i < 6; ++i) diag[i] = r->cov(i, i);
  JsonObject j = header(ListenType::kPose, channel);
  j.add("seq", static_cast<std::int64_t>(m.seq))
      .add("utime", static_cast<std::int64_t>(m.utime))
      .add("publish_utime", static_cast<std::int64_t>(m.publish_utime))
      .add("frame_id", m.frame_id)
      .addRaw("position", jsonArray(m.position, 3, "%.9g"))
      .addRaw("orientation", jsonArray(m.orientation, 4, "%.9g"))
      .addRaw("cov_diag", jsonArray(diag, 6, "%.6g"))
      .add("status", statusName(r->status))
      .add("motion_inliers", r->motion_inliers)
      .add("motion_residual_per_dof", r->motion_residual_per_dof, 3)
      .add("observation_nis_per_dof", r->observation_nis_per_dof, 3)
      .add("landmarks_observed", r->landmarks_observed)
      .add("search", searchName(r->search));
  return done(ListenType::kPose, j);
}

ListenLine statsLine(const std::string& channel, const std::uint8_t* d, std::size_t n) {
  svslam_lcm::stats_t m;
  Status s = drivers::decodeLcm(d, n, m);
  Result<drivers::StatsReport> r = s ? drivers::fromLcm(m) : Result<drivers::StatsReport>(s);
  if (!r) return failed(ListenType::kStats, r.status());
  std::string stages = "[";
  for (std::size_t i = 0; i < r->stages.size(); ++i) {
    JsonObject st;
    st.add("name", r->stages[i].name)
        .add("p50_ms", r->stages[i].p50_ms, 3)
        .add("p99_ms", r->stages[i].p99_ms, 3)
        .add("max_ms", r->stages[i].max_ms, 3);
    stages += (i ? ", " : "") + st.str();
  }
  std::string queues = "[";
  for (std::size_t i = 0; i < r->queues.size(); ++i) {
    JsonObject q;
    q.add("name", r->queues[i].name)
        .add("depth", r->queues[i].depth)
        .add("capacity", r->queues[i].capacity)
        .add("drops", r->queues[i].drops);
    queues += (i ? ", " : "") + q.str();
  }
  std::string stalls = "[";
  for (std::size_t i = 0; i < r->stalls.size(); ++i) {
    JsonObject st;
    st.add("stage", r->stalls[i].stage)
        .add("count", r->stalls[i].count)
        .add("longest_ms", r->stalls[i].longest_ms, 1);
    stalls += (i ? ", " : "") + st.str();
  }
  JsonObject j = header(ListenType::kStats, channel);
  j.add("utime", drivers::toUtime(r->t_ns))
      .add("frames_in", r->frames_in)
      .add("frames_out", r->frames_out)
      .add("frames_dropped", r->frames_dropped)
      .add("frames_tracked", r->frames_tracked)
      .addRaw("stages", stages + "]")
      .addRaw("queues", queues + "]")
      .add("e2e_p50_ms", r->e2e_p50_ms, 3)
      .add("e2e_p99_ms", r->e2e_p99_ms, 3)
      .add("e2e_max_ms", r->e2e_max_ms, 3)
      .add("commands_accepted", r->commands.accepted)
      .add("commands_refused", r->commands.refusedTotal())
      .add("stalled_stage", r->stalled_stage)
      .add("stalled_ms", r->stalled_ms, 1)
      .addRaw("stalls", stalls + "]");
  return done(ListenType::kStats, j);
}

ListenLine mapSummaryLine(const std::string& channel, const std::uint8_t* d, std::size_t n) {
  svslam_lcm::map_summary_t m;
  Status s = drivers::decodeLcm(d, n, m);
  Result<drivers::MapSummaryReport> r =
      s ? drivers::fromLcm(m) : Result<drivers::MapSummaryReport>(s);
  if (!r) return failed(ListenType::kMapSummary, r.status());
  JsonObject j = header(ListenType::kMapSummary, channel);
  j.add("utime", drivers::toUtime(r->t_ns))
      .add("landmarks_in_state", r->landmarks_in_state)
      .add("landmarks_in_map", r->landmarks_in_map)
      .add("num_points", static_cast<std::int64_t>(r->points_world.size()));
  return done(ListenType::kMapSummary, j);
}

// The tile's cells with data and their mean height.
ListenLine mapTileLine(const std::string& channel, const std::uint8_t* d, std::size_t n) {
  drivers::MapTileMessage m;
  if (Status s = drivers::decodeMapTile(d, n, m); !s) return failed(ListenType::kMapTile, s);
  std::int64_t valid = 0;
  double sum_m = 0.0;
  for (std::size_t k = 0; k < m.tile.height_m.size(); ++k) {
    if (m.tile.count[k] > 0.0f && std::isfinite(m.tile.height_m[k])) {
      ++valid;
      sum_m += m.tile.height_m[k];
    }
  }
  JsonObject j = header(ListenType::kMapTile, channel);
  j.add("seq", m.seq)
      .add("t_ns", static_cast<std::int64_t>(m.t_ns))
      .add("tile_i", m.tile_i)
      .add("tile_j", m.tile_j)
      .add("cells_per_side", m.tile.cols)
      .add("cell_m", m.tile.cell_m, 6)
      .add("valid_cells", valid)
      .add("mean_height_m", valid > 0 ? sum_m / static_cast<double>(valid) : NAN, 4);
  return done(ListenType::kMapTile, j);
}

// Every keyframe correction C_k: its capture time (us), translation (m), quaternion (w, x, y, z).
ListenLine correctionLine(const std::string& channel, const std::uint8_t* d, std::size_t n) {
  drivers::PoseCorrectionMessage m;
  if (Status s = drivers::decodePoseCorrection(d, n, m); !s)
    return failed(ListenType::kPoseCorrection, s);
  std::string utimes = "[", positions = "[", orientations = "[";
  for (std::size_t k = 0; k < m.keyframe_t_ns.size(); ++k) {
    const Eigen::Vector3d t = m.correction[k].translation();
    const Eigen::Quaterniond q(m.correction[k].rotation());
    const double p[3] = {t.x(), t.y(), t.z()};
    const double o[4] = {q.w(), q.x(), q.y(), q.z()};
    const char* sep = k ? ", " : "";
    utimes += sep + std::to_string(drivers::toUtime(m.keyframe_t_ns[k]));
    positions += sep + jsonArray(p, 3, "%.9g");
    orientations += sep + jsonArray(o, 4, "%.9g");
  }
  JsonObject j = header(ListenType::kPoseCorrection, channel);
  j.add("utime", drivers::toUtime(m.t_ns))
      .add("correction_seq", m.correction_seq)
      .add("part", m.part)
      .add("parts", m.parts)
      .add("frame_id", m.frame_id)
      .add("loops_accepted", m.loops_accepted)
      .add("keyframes_total", m.keyframes_total)
      .add("num_keyframes", static_cast<std::int64_t>(m.keyframe_t_ns.size()))
      .addRaw("keyframe_utime", utimes + "]")
      .addRaw("position", positions + "]")
      .addRaw("orientation", orientations + "]");
  return done(ListenType::kPoseCorrection, j);
}

ListenLine commandLine(const std::string& channel, const std::uint8_t* d, std::size_t n) {
  svslam_lcm::command_t m;
  if (Status s = drivers::decodeLcm(d, n, m); !s) return failed(ListenType::kCommand, s);
  JsonObject j = header(ListenType::kCommand, channel);
  j.add("utime", static_cast<std::int64_t>(m.utime))
      .add("seq", static_cast<std::int64_t>(m.seq))
      .add("command", m.command)
      .add("argument", m.argument)
      .add("has_token", !m.token.empty());
  return done(ListenType::kCommand, j);
}

ListenLine commandStatusLine(const std::string& channel, const std::uint8_t* d, std::size_t n) {
  svslam_lcm::command_status_t m;
  if (Status s = drivers::decodeLcm(d, n, m); !s) return failed(ListenType::kCommandStatus, s);
  JsonObject j = header(ListenType::kCommandStatus, channel);
  j.add("utime", static_cast<std::int64_t>(m.utime))
      .add("seq", static_cast<std::int64_t>(m.seq))
      .add("command", m.command)
      .add("ok", m.ok != 0)
      .add("message", m.message);
  return done(ListenType::kCommandStatus, j);
}

// Mean grey level of the width x height pixels of a `stride`-byte-per-row image.
double meanGrey(const std::vector<std::uint8_t>& img, int width, int height, int stride) {
  double sum = 0.0;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) sum += img[static_cast<std::size_t>(y) * stride + x];
  return sum / (static_cast<double>(width) * height);
}

ListenLine stereoImageLine(const std::string& channel, const std::uint8_t* d, std::size_t n) {
  svslam_lcm::stereo_image_t m;
  Status s = drivers::decodeLcm(d, n, m);
  if (s) s = drivers::validateStereoImage(m);
  if (!s) return failed(ListenType::kStereoImage, s);
  JsonObject j = header(ListenType::kStereoImage, channel);
  j.add("utime", static_cast<std::int64_t>(m.utime))
      .add("seq", static_cast<std::int64_t>(m.seq))
      .add("width", m.width)
      .add("height", m.height)
      .add("stride", m.stride)
      .add("f_px", m.f_px, 4)
      .add("cx_px", m.cx_px, 4)
      .add("cy_px", m.cy_px, 4)
      .add("baseline_m", m.baseline_m, 6)
      .add("left_mean", meanGrey(m.left, m.width, m.height, m.stride), 2)
      .add("right_mean", meanGrey(m.right, m.width, m.height, m.stride), 2);
  return done(ListenType::kStereoImage, j);
}

}  // namespace

const char* listenTypeName(ListenType t) {
  switch (t) {
    case ListenType::kPose:
      return "pose";
    case ListenType::kStats:
      return "stats";
    case ListenType::kMapSummary:
      return "map_summary";
    case ListenType::kMapTile:
      return "map_tile";
    case ListenType::kPoseCorrection:
      return "pose_correction";
    case ListenType::kCommand:
      return "command";
    case ListenType::kCommandStatus:
      return "command_status";
    case ListenType::kStereoImage:
      return "stereo_image";
    case ListenType::kUnknown:
      break;
  }
  return "unknown";
}

ListenType listenTypeOf(const std::uint8_t* data, std::size_t size) {
  if (size < 8) return ListenType::kUnknown;
  std::uint64_t h = 0;
  for (int i = 0; i < 8; ++i) h = (h << 8) | data[i];
  const auto hash = static_cast<std::int64_t>(h);
  if (hash == svslam_lcm::pose_t::getHash()) return ListenType::kPose;
  if (hash == svslam_lcm::stats_t::getHash()) return ListenType::kStats;
  if (hash == svslam_lcm::map_summary_t::getHash()) return ListenType::kMapSummary;
  if (hash == svslam_lcm::map_tile_t::getHash()) return ListenType::kMapTile;
  if (hash == svslam_lcm::pose_correction_t::getHash()) return ListenType::kPoseCorrection;
  if (hash == svslam_lcm::command_t::getHash()) return ListenType::kCommand;
  if (hash == svslam_lcm::command_status_t::getHash()) return ListenType::kCommandStatus;
  if (hash == svslam_lcm::stereo_image_t::getHash()) return ListenType::kStereoImage;
  return ListenType::kUnknown;
}

ListenLine listenLine(const std::string& channel, const std::uint8_t* data, std::size_t size) {
  switch (listenTypeOf(data, size)) {
    case ListenType::kPose:
      return poseLine(channel, data, size);
    case ListenType::kStats:
      return statsLine(channel, data, size);
    case ListenType::kMapSummary:
      return mapSummaryLine(channel, data, size);
    case ListenType::kMapTile:
      return mapTileLine(channel, data, size);
    case ListenType::kPoseCorrection:
      return correctionLine(channel, data, size);
    case ListenType::kCommand:
      return commandLine(channel, data, size);
    case ListenType::kCommandStatus:
      return commandStatusLine(channel, data, size);
    case ListenType::kStereoImage:
      return stereoImageLine(channel, data, size);
    case ListenType::kUnknown:
      break;
  }
  return {ListenType::kUnknown, "", "not an svslam_lcm message (unknown type hash)"};
}

}  // namespace svslam::cli
