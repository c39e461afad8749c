// Per-frame feature kernels of the stereo stage, one thread: corner detection (precise Harris,
// CornerDetector) and stereo point matching (ZNCC row search + continuity + recovery,
// StereoPointMatcher), with default parameters, on a rendered synthetic pair at 1024x768 (the
// `svslam run` default source) and on a KITTI odometry pair (1226x370) when the data is present.
// Items processed = corners detected (detect) or left points searched (stereo_match).
// The keyframes' ORB extraction (features/orb_extractor.hpp with KeyframeParams::defaultOrb: loop
// closing and relocalisation) on the rendered left images at 512x384 and 1024x768, with OpenCV's
// cv::ORB (as many features, FAST threshold 15, 8 levels) on the same image as the reference;
// items = keypoints.
#include <benchmark/benchmark.h>

#include <opencv2/features2d.hpp>

#include <string>
#include <vector>

#include "drivers/source/stereo_source.hpp"
#include "features/corner_detector.hpp"
#include "features/orb_extractor.hpp"
#include "features/stereo_point_matcher.hpp"
#include "loop/keyframe.hpp"

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

const Pair& synthetic512Pair() {
  static const Pair p = loadPair("synthetic:width=512,height=384");
  return p;
}

void runOrb(benchmark::State& st, const Pair& p) {
  if (!p.error.empty()) {
    st.SkipWithError(p.error.c_str());
    return;
  }
  const auto& img = p.frame.left;
  svslam::OrbExtractor orb(svslam::KeyframeParams::defaultOrb(), img.width(), img.height());
  std::vector<svslam::OrbKeypoint> kps;
  std::vector<svslam::OrbDescriptor> desc;
  std::int64_t items = 0;
  for (auto _ : st) {
    (void)orb.process(img.cview(), kps, desc);
    items += static_cast<std::int64_t>(kps.size());
    benchmark::DoNotOptimize(desc.data());
  }
  st.counters["keypoints"] = static_cast<double>(kps.size());
  st.SetItemsProcessed(items);
}

void runOpenCvOrb(benchmark::State& st, const Pair& p) {
  if (!p.error.empty()) {
    st.SkipWithError(p.error.c_str());
    return;
  }
  const auto& img = p.frame.left;
  const svslam::OrbParams op = svslam::KeyframeParams::defaultOrb();
  const cv::Mat m(img.height(), img.width(), CV_8UC1, const_cast<std::uint8_t*>(img.cview().row(0)),
                  static_cast<std::size_t>(img.cview().stride));
  auto orb = cv::ORB::create(op.grid_cols * op.grid_rows * op.max_per_cell, 1.2f, 8, 31, 0, 2,
                             cv::ORB::HARRIS_SCORE, 31, op.fast_threshold);
  std::vector<cv::KeyPoint> kps;
  cv::Mat desc;
  std::int64_t items = 0;
  for (auto _ : st) {
    orb->detectAndCompute(m, cv::noArray(), kps, desc);
    items += static_cast<std::int64_t>(kps.size());
    benchmark::DoNotOptimize(desc.data);
  }
  st.counters["keypoints"] = static_cast<double>(kps.size());
  st.SetItemsProcessed(items);
}

void BM_Orb_Synthetic512x384(benchmark::State& st) { runOrb(st, synthetic512Pair()); }
void BM_OpenCvOrb_Synthetic512x384(benchmark::State& st) { runOpenCvOrb(st, synthetic512Pair()); }
void BM_Orb_Synthetic1024x768(benchmark::State& st) { runOrb(st, syntheticPair()); }
void BM_OpenCvOrb_Synthetic1024x768(benchmark::State& st) { runOpenCvOrb(st, syntheticPair()); }
void BM_Detect_Synthetic1024x768(benchmark::State& st) { runDetect(st, syntheticPair()); }
void BM_StereoMatch_Synthetic1024x768(benchmark::State& st) { runStereoMatch(st, syntheticPair()); }
void BM_Detect_Kitti(benchmark::State& st) { runDetect(st, kittiPair()); }
void BM_StereoMatch_Kitti(benchmark::State& st) { runStereoMatch(st, kittiPair()); }

BENCHMARK(BM_Detect_Synthetic1024x768)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_StereoMatch_Synthetic1024x768)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Detect_Kitti)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_StereoMatch_Kitti)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Orb_Synthetic512x384)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_OpenCvOrb_Synthetic512x384)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Orb_Synthetic1024x768)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_OpenCvOrb_Synthetic1024x768)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
