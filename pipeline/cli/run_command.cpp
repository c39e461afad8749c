// svslam run: stereo visual odometry over a sequence, writing trajectories and stats.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <system_error>
#include <vector>

#include "drivers/stereo_source.hpp"
#include "odometry/stereo_odometry.hpp"
#include "pipeline/cli/arg_parser.hpp"
#include "pipeline/cli/commands.hpp"
#include "pipeline/cli/json_writer.hpp"
#include "pipeline/config/run_config.hpp"
#include "pipeline/run/run_outputs.hpp"
#include "pipeline/thread_pool_executor.hpp"

namespace svslam::cli {
namespace {

using Clock = std::chrono::steady_clock;

double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// Times the stages of the odometry through the library's observer hook.
class StageClock final : public StageObserver {
 public:
  explicit StageClock(run::StageTimes& times) : times_(times) {}
  void start() { last_ = Clock::now(); }
  void stageDone(const char* stage) override {
    const auto now = Clock::now();
    times_.add(stage, std::chrono::duration<double, std::milli>(now - last_).count());
    last_ = now;
  }

 private:
  run::StageTimes& times_;
  Clock::time_point last_;
};

struct RunSummary {
  int frames = 0;
  int tracked = 0;
  std::map<std::string, int> failure_counts;
  std::vector<std::pair<int, std::string>> failures;  // first ones, frame + reason
  double sum_corners = 0, sum_points = 0, sum_matches = 0, sum_inliers = 0;
  double sum_recovered = 0, sum_continuity_rejected = 0;
};

std::string statsJson(const config::RunConfig& cfg, const std::string& source,
                      const RunSummary& s, const run::StageTimes& times, const std::string& error) {
  JsonObject fails;
  for (const auto& [reason, n] : s.failure_counts) fails.add(reason, n);
  std::string list = "[";
  for (std::size_t i = 0; i < s.failures.size(); ++i) {
    JsonObject f;
    f.add("frame", s.failures[i].first).add("reason", s.failures[i].second);
    list += (i ? ", " : "") + f.str();
  }
  list += "]";
  const double n = std::max(1, s.frames);
  JsonObject j;
  j.add("source", source)
      .add("mode", "vo")
      .add("frames", s.frames)
      .add("frames_tracked", s.tracked)
      .add("frames_without_pose", s.frames - s.tracked)
      .addRaw("without_pose_reasons", fails.str())
      .addRaw("without_pose_frames", list)
      .add("mean_corners", s.sum_corners / n, 1)
      .add("mean_stereo_points", s.sum_points / n, 1)
      .add("mean_stereo_continuity_rejected", s.sum_continuity_rejected / n, 1)
      .add("mean_stereo_recovered", s.sum_recovered / n, 1)
      .add("mean_temporal_matches", s.sum_matches / n, 1)
      .add("mean_motion_inliers", s.sum_inliers / n, 1)
      .add("threads", cfg.threads)
      .add("dense_stereo", cfg.odometry.dense)
      .add("seed", static_cast<std::int64_t>(cfg.seed))
      .add("front_end_median_ms", times.median("front_end"), 3)
      .addRaw("stage_ms", times.json());
  if (!error.empty()) j.add("error", error);
  return j.str() + "\n";
}

}  // namespace

int runRun(const std::vector<std::string>& args) {
  ArgParser p("run",
              "Runs stereo visual odometry over a sequence (as fast as possible) and writes to\n"
              "the output folder: trajectory_kitti.txt (3x4 [R|t] per input frame, left camera\n"
              "in the first left camera's frame), trajectory_tum.txt, stats.json (frames,\n"
              "frames without a pose and why, per-stage time p50/p99/max in ms) and, when the\n"
              "source knows it, groundtruth_kitti.txt. Prints a JSON summary on stdout.");
  p.addOption("source", "SRC",
              "kitti:DIR, euroc:DIR or synthetic[:key=value,...] (default: the config's "
              "'source', else synthetic)");
  p.addOption("config", "FILE", "YAML configuration (documented example: config/svslam.yaml)");
  p.addOption("out", "DIR", "output folder (created if missing)", "svslam_out");
  p.addOption("max-frames", "N", "stop after N frames (0 = all; overrides the config)");
  p.addOption("threads", "T", "worker threads for stages that split work (overrides the config)");
  if (auto code = parseCommandLine(p, args)) return *code;
  auto fail = [](const Status& s) { return reportFailure("run", s); };

  config::RunConfig cfg;
  if (Status s = config::loadRunConfig(p.has("config") ? p.get("config") : "", cfg); !s)
    return fail(s);
  if (p.has("max-frames")) {
    auto n = p.getInt("max-frames", 0, 100000000);
    if (!n) return fail(n.status());
    cfg.max_frames = *n;
  }
  if (p.has("threads")) {
    auto n = p.getInt("threads", 1, 256);
    if (!n) return fail(n.status());
    cfg.threads = *n;
    cfg.odometry.dense_stereo.num_stripes = *n;
  }
  const std::string source_spec = p.has("source") ? p.get("source") : cfg.source;
  auto src = io::openStereoSource(source_spec);
  if (!src) return fail(src.status());
  io::StereoSource& source = **src;

  const std::string out_dir = p.get("out");
  std::error_code ec;
  std::filesystem::create_directories(out_dir, ec);
  if (ec || !std::filesystem::is_directory(out_dir))
    return fail(Status::ioError("cannot create output folder '" + out_dir + "'"));
  const std::string stats_path = out_dir + "/stats.json";

  StereoOdometry vo(cfg.odometry, source.calibration());
  if (!vo.initStatus()) return fail(vo.initStatus());
  std::unique_ptr<Executor> executor;
  if (cfg.threads > 1)
    executor = std::make_unique<ThreadPoolExecutor>(cfg.threads);
  else
    executor = std::make_unique<SerialExecutor>();

  run::TrajectoryWriter traj, gt;
  if (Status s = traj.open(out_dir + "/trajectory_kitti.txt", out_dir + "/trajectory_tum.txt"); !s)
    return fail(s);
  Eigen::Isometry3d T_gt;
  const bool has_gt = source.groundTruth(0, T_gt);
  if (has_gt) {
    if (Status s = gt.open(out_dir + "/groundtruth_kitti.txt", ""); !s) return fail(s);
  }

  run::StageTimes times;
  StageClock clock(times);
  RunSummary sum;
  io::StereoFrame frame;
  std::string error;
  while (cfg.max_frames == 0 || sum.frames < cfg.max_frames) {
    const auto t_load = Clock::now();
    auto more = source.next(frame);
    if (!more) {
      error = more.status().message();
      break;
    }
    if (!*more) break;
    times.add("load", msSince(t_load));
    OdometryFrameResult r;
    const auto t0 = Clock::now();
    clock.start();
    if (Status s = vo.process(frame.left.cview(), frame.right.cview(), r, *executor, &clock); !s) {
      error = "frame " + std::to_string(frame.index) + ": " + s.message();
      break;
    }
    times.add("front_end", msSince(t0));
    ++sum.frames;
    if (r.tracked) {
      ++sum.tracked;
    } else {
      ++sum.failure_counts[r.failure];
      if (sum.failures.size() < 100) sum.failures.emplace_back(frame.index, r.failure);
    }
    sum.sum_corners += r.corners;
    sum.sum_points += r.stereo_points;
    sum.sum_matches += r.temporal_matches;
    sum.sum_inliers += r.inliers;
    sum.sum_recovered += r.stereo_stats.recovered;
    sum.sum_continuity_rejected += r.stereo_stats.continuity_rejected;
    if (Status s = traj.append(frame.t_ns, r.T_first_cam); !s) {
      error = s.message();
      break;
    }
    if (has_gt && source.groundTruth(frame.index, T_gt)) {
      if (Status s = gt.append(frame.t_ns, T_gt); !s) {
        error = s.message();
        break;
      }
    }
  }
  traj.close();
  gt.close();
  if (Status s = run::writeFileAtomic(stats_path, statsJson(cfg, source_spec, sum, times, error));
      !s)
    return fail(s);
  if (!error.empty()) return fail(Status::ioError(error));
  JsonObject j;
  j.add("source", source_spec)
      .add("out", out_dir)
      .add("frames", sum.frames)
      .add("frames_tracked", sum.tracked)
      .add("front_end_median_ms", times.median("front_end"), 3);
  std::printf("%s\n", j.str().c_str());
  return 0;
}

}  // namespace svslam::cli
