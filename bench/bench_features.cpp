// Per-frame feature kernels of the stereo stage, one thread: corner detection (precise Harris,
// CornerDetector) and stereo point matching (ZNCC row search + continuity + recovery,
// StereoPointMatcher), with default parameters, on a rendered synthetic pair at 1024x768 (the
// `svslam run` default source) and on a KITTI odometry pair (1226x370) when the data is present.
// Items processed = corners detected (detect) or left points searched (stereo_match).
#include <benchmark/benchmark.h>

#include <string>
#include <vector>

#include "drivers/source/stereo_source.hpp"
#include "features/corner_detector.hpp"
#include "features/stereo_point_matcher.hpp"

namespace {

struct Pair {
  svslam::drivers::StereoFrame frame;
  std::vector<Eigen::Vector2f> corners;  // detected with default parameters
  std::string error;
};

Pair loadPair(const std::string& spec) {
  Pair p;
  auto src = svslam::drivers::openStereoSource(spec);
  if (!src) {
    p.error = src.status().message();
    return p;
  }
  auto more = (*src)->next(p.frame);
  if (!more || !*more) {
    p.error = "no frame from " + spec;
    return p;
  }
  const auto& img = p.frame.left;
  svslam::CornerDetector det(svslam::CornerParams{}, img.width(), img.height());
  std::vector<svslam::Corner> cs;
  (void)det.process(img.cview(), cs);
  for (const auto& c : cs) p.corners.emplace_back(c.x_px, c.y_px);
  return p;
}

const Pair& syntheticPair() {
  static const Pair p = loadPair("synthetic");
  return p;
}

const Pair& kittiPair() {
  static const Pair p = loadPair("kitti:" + std::string(SVSLAM_DATA_DIR) + "/kitti_odometry_seq_a");
  return p;
}

void runDetect(benchmark::State& st, const Pair& p) {
  if (!p.error.empty()) {
    st.SkipWithError(p.error.c_str());
    return;
  }
  const auto& img = p.frame.left;
  svslam::CornerDetector det(svslam::CornerParams{}, img.width(), img.height());
  std::vector<svslam::Corner> out;
  out.reserve(4096);
  std::int64_t items = 0;
  for (auto _ : st) {
    (void)det.process(img.cview(), out);
    items += static_cast<std::int64_t>(out.size());
    benchmark::DoNotOptimize(out.data());
  }
  st.counters["corners"] = static_cast<double>(out.size());
  st.SetItemsProcessed(items);
}

void runStereoMatch(benchmark::State& st, const Pair& p) {
  if (!p.error.empty()) {
    st.SkipWithError(p.error.c_str());
    return;
  }
  svslam::StereoPointMatcher m(svslam::StereoMatchParams{});
  std::vector<svslam::StereoMatch> out;
  svslam::StereoMatchStats stats;
  std::int64_t items = 0;
  for (auto _ : st) {
    (void)m.process(p.frame.left.cview(), p.frame.right.cview(), p.corners, {}, out, stats);
    items += static_cast<std::int64_t>(p.corners.size());
    benchmark::DoNotOptimize(out.data());
  }
  st.counters["matched"] = static_cast<double>(stats.matched);
  st.SetItemsProcessed(items);
}

void BM_Detect_Synthetic1024x768(benchmark::State& st) { runDetect(st, syntheticPair()); }
void BM_StereoMatch_Synthetic1024x768(benchmark::State& st) { runStereoMatch(st, syntheticPair()); }
void BM_Detect_Kitti(benchmark::State& st) { runDetect(st, kittiPair()); }
void BM_StereoMatch_Kitti(benchmark::State& st) { runStereoMatch(st, kittiPair()); }

BENCHMARK(BM_Detect_Synthetic1024x768)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_StereoMatch_Synthetic1024x768)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Detect_Kitti)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_StereoMatch_Kitti)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
