// svslam run: stereo visual odometry over a sequence, writing trajectories and stats.
#include <algorithm>
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
#include "slam/slam_system.hpp"
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
  // EKF mode.
  double sum_observed = 0, sum_reperceived = 0, sum_gated = 0, sum_in_state = 0;
  double sum_visible = 0, sum_no_match = 0, sum_no_stereo = 0;
  int max_in_state = 0, landmarks_in_map = 0, added = 0, retired = 0;
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
      .add("mode", cfg.mode)
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
      .add("front_end_median_ms", times.median("front_end"), 3);
  if (cfg.mode == "ekf") {
    j.add("landmarks_in_state_mean", s.sum_in_state / n, 1)
        .add("landmarks_in_state_max", s.max_in_state)
        .add("landmarks_in_map", s.landmarks_in_map)
        .add("landmarks_added", s.added)
        .add("landmarks_retired", s.retired)
        .add("mean_landmarks_observed", s.sum_observed / n, 1)
        .add("mean_landmarks_reperceived", s.sum_reperceived / n, 2)
        .add("mean_observations_gated", s.sum_gated / n, 2)
        .add("mean_landmarks_predicted_visible", s.sum_visible / n, 1)
        .add("mean_landmark_search_no_match", s.sum_no_match / n, 2)
        .add("mean_landmark_search_no_stereo", s.sum_no_stereo / n, 2)
        .add("ekf_median_ms", times.median("ekf"), 3);
  }
  j.addRaw("stage_ms", times.json());
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
              "source knows it, groundtruth_kitti.txt. In ekf mode (default) also\n"
              "pose_covariance.txt (6x6 per frame, row-major, [rot rad, trans m]) and\n"
              "landmarks.ply (every landmark, position + 1-sigma radii). Prints a JSON summary.");
  p.addOption("source", "SRC",
              "kitti:DIR, euroc:DIR or synthetic[:key=value,...] (default: the config's "
              "'source', else synthetic)");
  p.addOption("config", "FILE", "YAML configuration (documented example: config/svslam.yaml)");
  p.addOption("out", "DIR", "output folder (created if missing)", "svslam_out");
  p.addOption("max-frames", "N", "stop after N frames (0 = all; overrides the config)");
  p.addOption("threads", "T", "worker threads for stages that split work (overrides the config)");
  p.addOption("mode", "ekf|vo",
              "ekf: EKF SLAM over pose and landmarks; vo: pure visual odometry (overrides the "
              "config; default ekf)");
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
  if (p.has("mode")) {
    cfg.mode = p.get("mode");
    if (cfg.mode != "ekf" && cfg.mode != "vo")
      return fail(Status::invalidArgument("--mode: unknown mode '" + cfg.mode + "' (use ekf or vo)"));
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

  const bool ekf_mode = cfg.mode == "ekf";
  std::unique_ptr<StereoOdometry> vo;
  std::unique_ptr<SlamSystem> slam;
  if (ekf_mode) {
    slam = std::make_unique<SlamSystem>(cfg.slam, cfg.odometry, source.calibration());
    if (!slam->initStatus()) return fail(slam->initStatus());
  } else {
    vo = std::make_unique<StereoOdometry>(cfg.odometry, source.calibration());
    if (!vo->initStatus()) return fail(vo->initStatus());
  }
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
  run::LineWriter cov_file;
  if (ekf_mode) {
    if (Status s = cov_file.open(out_dir + "/pose_covariance.txt"); !s) return fail(s);
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
    SlamFrameResult sr;
    OdometryFrameResult& r = sr.odometry;
    const auto t0 = Clock::now();
    clock.start();
    const Status ps =
        ekf_mode ? slam->process(frame.left.cview(), frame.right.cview(), sr, *executor, &clock)
                 : vo->process(frame.left.cview(), frame.right.cview(), r, *executor, &clock);
    if (!ps) {
      error = "frame " + std::to_string(frame.index) + ": " + ps.message();
      break;
    }
    times.add("front_end", msSince(t0));
    if (ekf_mode) {
      sum.sum_observed += sr.observed;
      sum.sum_reperceived += sr.reperceived;
      sum.sum_gated += sr.gated;
      sum.sum_visible += sr.predicted_visible;
      sum.sum_no_match += sr.search_no_match;
      sum.sum_no_stereo += sr.search_no_stereo;
      sum.sum_in_state += sr.landmarks_in_state;
      sum.max_in_state = std::max(sum.max_in_state, sr.landmarks_in_state);
      sum.landmarks_in_map = sr.landmarks_in_map;
      sum.added += sr.added;
      sum.retired += sr.retired;
    }
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
    if (Status s = traj.append(frame.t_ns, ekf_mode ? sr.T_world_cam : r.T_first_cam); !s) {
      error = s.message();
      break;
    }
    if (ekf_mode) {
      std::string line;
      char num[32];
      for (int i = 0; i < 36; ++i) {
        std::snprintf(num, sizeof num, "%s%.9e", i ? " " : "", sr.pose_cov(i / 6, i % 6));
        line += num;
      }
      if (Status s = cov_file.append(line); !s) {
        error = s.message();
        break;
      }
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
  cov_file.close();
  if (ekf_mode) {
    std::vector<run::PlyLandmark> ply;
    for (const MapLandmark& m : slam->map())
      ply.push_back({m.id, m.p_world, m.cov.diagonal().cwiseMax(0.0).cwiseSqrt(), m.active,
                     m.observations});
    if (Status s = run::writeLandmarksPly(out_dir + "/landmarks.ply", ply); !s && error.empty())
      error = s.message();
  }
  if (Status s = run::writeFileAtomic(stats_path, statsJson(cfg, source_spec, sum, times, error));
      !s)
    return fail(s);
  if (!error.empty()) return fail(Status::ioError(error));
  JsonObject j;
  j.add("source", source_spec)
      .add("mode", cfg.mode)
      .add("out", out_dir)
      .add("frames", sum.frames)
      .add("frames_tracked", sum.tracked)
      .add("front_end_median_ms", times.median("front_end"), 3);
  std::printf("%s\n", j.str().c_str());
  return 0;
}

}  // namespace svslam::cli
