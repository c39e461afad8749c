// svslam listen: prints the poses (with covariance), statistics and elevation map tiles
// published on LCM, one JSON line each, as received by a separate process.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "drivers/lcm/lcm_map_tile.hpp"
#include "drivers/lcm/lcm_transport.hpp"
#include "pipeline/cli/arg_parser.hpp"
#include "pipeline/cli/commands.hpp"
#include "pipeline/cli/json_writer.hpp"

namespace svslam::cli {
namespace {

std::string jsonArray(const double* v, int n, const char* fmt) {
  std::string s = "[";
  char buf[64];
  for (int i = 0; i < n; ++i) {
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
  }
  return "unknown";
}

std::string poseLine(const svslam_lcm::pose_t& m, const drivers::PoseReport& r) {
  double diag[6];
  for (int i = 0; i < 6; ++i) diag[i] = r.cov(i, i);
  JsonObject j;
  j.add("type", "pose")
      .add("seq", static_cast<std::int64_t>(m.seq))
      .add("utime", static_cast<std::int64_t>(m.utime))
      .add("publish_utime", static_cast<std::int64_t>(m.publish_utime))
      .add("frame_id", m.frame_id)
      .addRaw("position", jsonArray(m.position, 3, "%.9g"))
      .addRaw("orientation", jsonArray(m.orientation, 4, "%.9g"))
      .addRaw("cov_diag", jsonArray(diag, 6, "%.6g"))
      .add("status", statusName(r.status));
  return j.str();
}

std::string statsLine(const drivers::StatsReport& r) {
  std::string stages = "[";
  for (std::size_t i = 0; i < r.stages.size(); ++i) {
    JsonObject s;
    s.add("name", r.stages[i].name)
        .add("p50_ms", r.stages[i].p50_ms, 3)
        .add("p99_ms", r.stages[i].p99_ms, 3)
        .add("max_ms", r.stages[i].max_ms, 3);
    stages += (i ? ", " : "") + s.str();
  }
  std::string queues = "[";
  for (std::size_t i = 0; i < r.queues.size(); ++i) {
    JsonObject q;
    q.add("name", r.queues[i].name)
        .add("depth", r.queues[i].depth)
        .add("capacity", r.queues[i].capacity)
        .add("drops", r.queues[i].drops);
    queues += (i ? ", " : "") + q.str();
  }
  JsonObject j;
  j.add("type", "stats")
      .add("utime", drivers::toUtime(r.t_ns))
      .add("frames_in", r.frames_in)
      .add("frames_out", r.frames_out)
      .add("frames_dropped", r.frames_dropped)
      .add("frames_tracked", r.frames_tracked)
      .addRaw("stages", stages + "]")
      .addRaw("queues", queues + "]")
      .add("e2e_p50_ms", r.e2e_p50_ms, 3)
      .add("e2e_p99_ms", r.e2e_p99_ms, 3)
      .add("e2e_max_ms", r.e2e_max_ms, 3)
      .add("commands_accepted", r.commands.accepted)
      .add("commands_refused", r.commands.refusedTotal());
  return j.str();
}

// One line per map tile: its index, time, the cells with data and their mean height.
std::string mapTileLine(const drivers::MapTileMessage& m) {
  std::int64_t valid = 0;
  double sum_m = 0.0;
  for (std::size_t k = 0; k < m.tile.height_m.size(); ++k) {
    if (m.tile.count[k] > 0.0f && std::isfinite(m.tile.height_m[k])) {
      ++valid;
      sum_m += m.tile.height_m[k];
    }
  }
  JsonObject j;
  j.add("type", "map_tile")
      .add("seq", m.seq)
      .add("t_ns", static_cast<std::int64_t>(m.t_ns))
      .add("tile_i", m.tile_i)
      .add("tile_j", m.tile_j)
      .add("cells_per_side", m.tile.cols)
      .add("cell_m", m.tile.cell_m, 6)
      .add("valid_cells", valid)
      .add("mean_height_m", valid > 0 ? sum_m / static_cast<double>(valid) : NAN, 4);
  return j.str();
}

}  // namespace

int runListen(const std::vector<std::string>& args) {
  const drivers::LcmParams defaults;
  ArgParser p("listen",
              "Subscribes to the poses (statistics, map tiles) svslam publishes on LCM and\n"
              "prints one JSON line per message on stdout: poses with seq, utime,\n"
              "publish_utime (us), position (m), orientation (w, x, y, z), the covariance\n"
              "diagonal [rot rad^2, trans m^2] and the tracking status; map tiles with t_ns,\n"
              "tile_i, tile_j, the cells with data and their mean height (m). Exits 0 after\n"
              "--count poses (--count 0: at the end of a replayed file:// log), 1 when no\n"
              "pose arrives within --timeout-s or a replayed log ends before --count poses.");
  p.addOption("url", "URL", "LCM URL", defaults.url);
  p.addOption("channel", "CHANNEL", "pose channel", defaults.pose_channel);
  p.addOption("stats-channel", "CHANNEL", "statistics channel", defaults.stats_channel);
  p.addFlag("no-stats", "do not print statistics");
  p.addOption("map-tile-channel", "CHANNEL", "elevation map tile channel",
              defaults.map_tile_channel);
  p.addFlag("no-map-tiles", "do not print map tiles");
  p.addOption("count", "N", "exit 0 after N poses (0: never)", "0");
  p.addOption("timeout-s", "S", "longest wait for the next pose, seconds", "10");
  if (auto code = parseCommandLine(p, args)) return *code;
  auto fail = [](const Status& s) { return reportFailure("listen", s); };

  auto count = p.getInt("count", 0, 1'000'000'000);
  if (!count) return fail(count.status());
  auto timeout_s = p.getDouble("timeout-s");
  if (!timeout_s) return fail(timeout_s.status());
  if (!(*timeout_s > 0.0 && *timeout_s <= 86400.0))
    return fail(Status::invalidArgument("--timeout-s must be in (0, 86400]"));

  drivers::LcmParams lp;
  lp.url = p.get("url");
  lp.pose_channel = p.get("channel");
  lp.stats_channel = p.get("stats-channel");
  lp.map_tile_channel = p.get("map-tile-channel");
  auto link = drivers::LcmLink::open(lp);
  if (!link) return fail(link.status());

  using Clock = std::chrono::steady_clock;
  const auto gap =
      std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(*timeout_s));
  auto deadline = Clock::now() + gap;
  std::int64_t received = 0, malformed = 0;
  const std::int64_t wanted = *count;
  auto on_pose = [&](const std::uint8_t* d, std::size_t n) {
    if (wanted > 0 && received >= wanted) return;
    svslam_lcm::pose_t m;
    Status s = drivers::decodeLcm(d, n, m);
    Result<drivers::PoseReport> r = s ? drivers::fromLcm(m) : Result<drivers::PoseReport>(s);
    if (!r) {
      ++malformed;
      std::fprintf(stderr, "svslam listen: skipped a malformed pose: %s\n",
                   r.status().message().c_str());
      return;
    }
    std::printf("%s\n", poseLine(m, *r).c_str());
    std::fflush(stdout);
    ++received;
    deadline = Clock::now() + gap;
  };
  auto on_stats = [&](const std::uint8_t* d, std::size_t n) {
    svslam_lcm::stats_t m;
    Status s = drivers::decodeLcm(d, n, m);
    Result<drivers::StatsReport> r = s ? drivers::fromLcm(m) : Result<drivers::StatsReport>(s);
    if (!r) return;
    std::printf("%s\n", statsLine(*r).c_str());
    std::fflush(stdout);
  };
  auto on_map_tile = [&](const std::uint8_t* d, std::size_t n) {
    drivers::MapTileMessage m;
    if (Status s = drivers::decodeMapTile(d, n, m); !s) {
      std::fprintf(stderr, "svslam listen: skipped a malformed map tile: %s\n",
                   s.message().c_str());
      return;
    }
    std::printf("%s\n", mapTileLine(m).c_str());
    std::fflush(stdout);
  };
  if (auto id = (*link)->subscribeRaw(lp.pose_channel, on_pose); !id) return fail(id.status());
  if (!p.flag("no-map-tiles")) {
    if (auto id = (*link)->subscribeRaw(lp.map_tile_channel, on_map_tile); !id)
      return fail(id.status());
  }
  if (!p.flag("no-stats")) {
    if (auto id = (*link)->subscribeRaw(lp.stats_channel, on_stats); !id) return fail(id.status());
  }
  // One message at a time, so that the loop ends right after the N-th pose (a replayed log may
  // end just after it).
  const bool replay = lp.url.rfind("file://", 0) == 0;
  while (wanted == 0 || received < wanted) {
    const auto left = deadline - Clock::now();
    if (left <= Clock::duration::zero()) {
      char secs[32];
      std::snprintf(secs, sizeof secs, "%g", *timeout_s);
      return fail(Status::notFound("no pose on '" + lp.pose_channel + "' via '" + lp.url +
                                   "' within " + secs + " s (received " + std::to_string(received) +
                                   (wanted ? " of " : "") + (wanted ? std::to_string(wanted) : "") +
                                   ", " + std::to_string(malformed) + " malformed)"));
    }
    const auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(left).count();
    auto handled = (*link)->handle(static_cast<int>(std::clamp<long long>(ms, 0, 100)));
    if (!handled && replay && wanted == 0) return 0;  // the whole log was printed
    if (!handled && replay)
      return fail(Status::notFound("the replayed log '" + lp.url + "' ended after " +
                                   std::to_string(received) + " of the " + std::to_string(wanted) +
                                   " poses wanted (" + std::to_string(malformed) + " malformed)"));
    if (!handled) return fail(handled.status());
  }
  return 0;
}

}  // namespace svslam::cli
