// End-to-end latency of the threaded pipeline (capture instant -> pose published) replaying a
// recorded sequence read into memory first, paced at a fixed rate as if captured live; plus the
// throughput as fast as possible. Each scenario also runs the same frames with --sequential as
// the in-run reference: its per-frame processing time is what one thread would take.
//
//   bench_latency [--scenario blimp10|kitti10|fast640|all] [--frames N] [--threads T]
//                 [--backend auto|scalar|avx2|avx512|neon]
//
// --backend forces the dense stereo kernels (default: the best the CPU has), e.g. avx2 on an
// AVX-512 machine to see what a machine without AVX-512 would take.
//
// Scenarios (the targets):
//   blimp10  synthetic blimp flight 1024x768 at 10 Hz, dense stereo and mapper on: p99 latency
//            <= 60 ms, zero drops. Dense stereo searches the blimp's disparity band, [48, 112) px:
//            f b / d = 1951 px m / d, depths 17 to 41 m (the flight is at 25-30 m over +-3 m of
//            relief), as a blimp's configuration would;
//   kitti10  KITTI odometry seq A (../shared/data) at 10 Hz: zero drops (skipped if absent);
//   fast640  synthetic 640x480 as fast as possible: >= 20 frames per second end to end;
//   loop10   blimp10 over two laps of a 70 m loop (loops from the second lap on) with loop
//            closing on (needs --vocabulary FILE, from `svslam train-vocabulary`, e.g. the one
//            scripts/loop_figures.sh trains at 1024x768), beside the same frames without it in
//            the same run: the estimator's p99 unchanged while the back end optimises (skipped
//            without --vocabulary).
// Prints one JSON object per scenario.
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "drivers/source/preloaded_source.hpp"
#include "drivers/source/stereo_source.hpp"
#include "pipeline/config/run_config.hpp"
#include "pipeline/realtime/pipeline_runner.hpp"
#include "pipeline/realtime/slam_stages.hpp"
#include "simd/stereo_kernels.hpp"

using namespace svslam;

namespace {

simd::Backend g_dense_backend = simd::Backend::kAuto;

struct Outcome {
  bool ok = false;
  rt::PipelineReport report;
  double map_p50_ms = 0.0;  // the mapper's time per fused frame (NaN without the mapper)
};

std::unique_ptr<drivers::PreloadedSource> load(const std::string& spec, int frames) {
  auto src = drivers::openStereoSource(spec);
  if (!src) {
    std::fprintf(stderr, "bench_latency: %s\n", src.status().message().c_str());
    return nullptr;
  }
  auto pre = drivers::preload(std::move(*src), frames);
  if (!pre) {
    std::fprintf(stderr, "bench_latency: %s\n", pre.status().message().c_str());
    return nullptr;
  }
  return std::move(*pre);
}

Outcome runOnce(drivers::PreloadedSource* frames_in_memory, double rate_hz, bool sequential,
                int threads, int dense_min_px = 0, int dense_max_px = 0,
                const std::function<void(config::RunConfig&)>& tweak = {},
                std::string* loop_json = nullptr) {
  Outcome o;
  if (!frames_in_memory) return o;
  drivers::PreloadedSource& source = *frames_in_memory;
  source.rewind();
  config::RunConfig cfg;
  config::applyThreads(cfg, threads);
  cfg.pipeline.runner.sequential = sequential;
  cfg.pipeline.runner.rate_hz = rate_hz;
  cfg.odometry.dense_stereo.backend = g_dense_backend;
  if (dense_max_px > 0) {
    cfg.odometry.dense_stereo.min_disp = dense_min_px;
    cfg.odometry.dense_stereo.max_disp = dense_max_px;
  }
  if (tweak) tweak(cfg);
  const std::string out =
      (std::filesystem::temp_directory_path() / "svslam_bench_latency").string();
  std::filesystem::create_directories(out);
  rt::SlamStages work(cfg, source, out, nullptr);
  if (Status s = work.init(); !s) {
    std::fprintf(stderr, "bench_latency: %s\n", s.message().c_str());
    return o;
  }
  const rt::PipelineOptions& opts = cfg.pipeline.runner;
  // As for a camera: a late frame is dropped, and counted.
  rt::PipelineRunner runner(
      opts, work.graph(rate_hz > 0 ? rt::EdgePolicy::kNewest : rt::EdgePolicy::kBlocking));
  std::vector<std::unique_ptr<rt::FrameSlot>> slots;
  for (int i = 0; i < runner.slotsNeeded(); ++i) slots.push_back(std::make_unique<rt::FrameSlot>());
  rt::PipelineControl control;
  const Status s = runner.run(slots, control, nullptr);
  (void)work.finish();
  if (!s) std::fprintf(stderr, "bench_latency: %s\n", s.message().c_str());
  o.ok = s.isOk();
  o.report = runner.report();
  o.map_p50_ms = work.stageTimes().median("map");
  if (loop_json) *loop_json = work.loopJson();
  return o;
}

void print(const char* name, const std::string& spec, double rate_hz, const Outcome& thr,
           const Outcome& seq, const char* target) {
  const rt::PipelineReport& r = thr.report;
  const rt::PipelineReport& q = seq.report;
  // One thread's time per frame: the sum of the stage times of the sequential run.
  const double seq_frame_ms =
      q.stage("stereo").p50_ms + q.stage("estimator").p50_ms + q.stage("publisher").p50_ms;
  std::printf(
      "{\"scenario\": \"%s\", \"source\": \"%s\", \"rate_hz\": %.1f, \"frames\": %lld, "
      "\"published\": %lld, \"dropped\": %lld, \"latency_p50_ms\": %.2f, \"latency_p99_ms\": %.2f, "
      "\"latency_max_ms\": %.2f, \"fps\": %.2f, \"stereo_p50_ms\": %.2f, \"estimator_p50_ms\": "
      "%.2f, "
      "\"sequential_fps\": %.2f, \"sequential_frame_p50_ms\": %.2f, "
      "\"threaded_over_sequential_fps\": %.2f, \"map_p50_ms\": %.2f, "
      "\"map_skipped_busy\": %lld, \"dense_backend\": \"%s\", \"target\": \"%s\"}\n",
      name, spec.c_str(), rate_hz, static_cast<long long>(r.captured),
      static_cast<long long>(r.published), static_cast<long long>(r.dropped), r.end_to_end.p50_ms,
      r.end_to_end.p99_ms, r.end_to_end.max_ms, r.fps, r.stage("stereo").p50_ms,
      r.stage("estimator").p50_ms, q.fps, seq_frame_ms, q.fps > 0 ? r.fps / q.fps : 0.0,
      thr.map_p50_ms, static_cast<long long>(r.after_publish_skipped),
      simd::backendName(g_dense_backend == simd::Backend::kAuto ? simd::bestBackend()
                                                                : g_dense_backend),
      target);
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  std::string scenario = "all", vocabulary;
  int frames = 100, threads = 1;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--scenario" && i + 1 < argc) {
      scenario = argv[++i];
    } else if (a == "--frames" && i + 1 < argc) {
      frames = std::atoi(argv[++i]);
    } else if (a == "--threads" && i + 1 < argc) {
      threads = std::atoi(argv[++i]);
    } else if (a == "--vocabulary" && i + 1 < argc) {
      vocabulary = argv[++i];
    } else if (a == "--backend" && i + 1 < argc) {
      if (!simd::parseBackend(argv[++i], g_dense_backend) ||
          !simd::backendAvailable(g_dense_backend)) {
        std::fprintf(stderr, "bench_latency: backend '%s' unknown or not on this CPU\n", argv[i]);
        return 2;
      }
    } else {
      std::fprintf(stderr,
                   "usage: bench_latency [--scenario blimp10|kitti10|fast640|all] [--frames N] "
                   "[--threads T] [--backend auto|scalar|avx2|avx512|neon] [--vocabulary FILE]\n");
      return a == "--help" ? 0 : 2;
    }
  }
  if (frames < 2 || threads < 1) {
    std::fprintf(stderr, "bench_latency: --frames must be >= 2 and --threads >= 1\n");
    return 2;
  }
  auto scenarioOn = [&](const char* s) { return scenario == "all" || scenario == s; };
  int failures = 0;
  if (scenarioOn("blimp10")) {
    const std::string spec = "synthetic:frames=" + std::to_string(frames);
    auto mem = load(spec, frames);
    const Outcome thr = runOnce(mem.get(), 10.0, false, threads, 48, 112);
    const Outcome seq = runOnce(mem.get(), 0.0, true, threads, 48, 112);
    failures += !thr.ok || !seq.ok;
    print("blimp10", spec, 10.0, thr, seq, "p99 <= 60 ms, 0 dropped");
  }
  if (scenarioOn("kitti10")) {
    const std::string dir = std::string(SVSLAM_DATA_DIR) + "/kitti_odometry_seq_a";
    if (!std::filesystem::exists(dir + "/calib.txt")) {
      std::printf("{\"scenario\": \"kitti10\", \"skipped\": \"%s not found\"}\n", dir.c_str());
    } else {
      auto mem = load("kitti:" + dir, frames);
      const Outcome thr = runOnce(mem.get(), 10.0, false, threads);
      const Outcome seq = runOnce(mem.get(), 0.0, true, threads);
      failures += !thr.ok || !seq.ok;
      print("kitti10", "kitti:" + dir, 10.0, thr, seq, "0 dropped");
    }
  }
  if (scenarioOn("fast640")) {
    const std::string spec = "synthetic:width=640,height=480,frames=" + std::to_string(frames);
    auto mem = load(spec, frames);
    const Outcome thr = runOnce(mem.get(), 0.0, false, threads);
    const Outcome seq = runOnce(mem.get(), 0.0, true, threads);
    failures += !thr.ok || !seq.ok;
    print("fast640", spec, 0.0, thr, seq, ">= 20 fps");
  }
  if (scenarioOn("loop10")) {
    const int lap = std::max(frames / 2, 2);
    const std::string spec = "synthetic:frames=" + std::to_string(2 * lap) +
                             ",loop_frames=" + std::to_string(lap) + ",loop_length_m=70";
    if (vocabulary.empty()) {
      std::printf("{\"scenario\": \"loop10\", \"skipped\": \"needs --vocabulary FILE\"}\n");
    } else {
      auto mem = load(spec, 2 * lap);
      const auto with_loop = [&](config::RunConfig& c) {
        c.loop_enabled = true;
        c.loop_vocabulary = vocabulary;
      };
      std::string loop_json;  // stats.json's loop object without the list of loops
      const Outcome off = runOnce(mem.get(), 10.0, false, threads, 48, 112);
      const Outcome on = runOnce(mem.get(), 10.0, false, threads, 48, 112, with_loop, &loop_json);
      failures += !off.ok || !on.ok;
      if (const std::size_t cut = loop_json.find(", \"accepted\""); cut != std::string::npos)
        loop_json = loop_json.substr(0, cut) + "}";
      const rt::LatencySummary e_off = off.report.stage("estimator"), e_on = on.report.stage("estimator");
      std::printf(
          "{\"scenario\": \"loop10\", \"source\": \"%s\", \"rate_hz\": 10.0, \"published\": %lld, "
          "\"dropped\": %lld, \"estimator_p50_ms\": %.2f, \"estimator_p99_ms\": %.2f, "
          "\"estimator_p99_without_loop_ms\": %.2f, \"estimator_p99_ratio\": %.3f, "
          "\"latency_p99_ms\": %.2f, \"latency_p99_without_loop_ms\": %.2f, "
          "\"dropped_without_loop\": %lld, \"loop\": %s, "
          "\"target\": \"estimator p99 unchanged (ratio ~1), 0 dropped\"}\n",
          spec.c_str(), static_cast<long long>(on.report.published),
          static_cast<long long>(on.report.dropped), e_on.p50_ms, e_on.p99_ms, e_off.p99_ms,
          e_off.p99_ms > 0 ? e_on.p99_ms / e_off.p99_ms : 0.0, on.report.end_to_end.p99_ms,
          off.report.end_to_end.p99_ms, static_cast<long long>(off.report.dropped),
          loop_json.empty() ? "{}" : loop_json.c_str());
      std::fflush(stdout);
    }
  }
  return failures ? 1 : 0;
}
