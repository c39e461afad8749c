// Dense stereo benchmarks: svslam census and SAD beside cv::StereoBM and cv::StereoSGBM on the
// same images in the same binary, at 640x480 and 1024x768, 64 and 128 disparities, 1 and 2
// threads. After the runs, prints the time ratios svslam / OpenCV for each configuration.
//
// Images: Middlebury v2 "cones" (from ../shared/data) resized to the benchmark size; when the
// data folder is absent, a seeded synthetic textured pair shifted by 20 px is used instead.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <string>

#include "pipeline/thread_pool_executor.hpp"
#include "stereo/dense_stereo.hpp"

namespace {

struct Pair {
  cv::Mat left, right;
};

const Pair& pairOfSize(int w, int h) {
  static std::map<std::pair<int, int>, Pair> cache;
  auto key = std::make_pair(w, h);
  if (auto it = cache.find(key); it != cache.end()) return it->second;
  Pair p;
  const std::string dir = std::string(SVSLAM_DATA_DIR) + "/middlebury_v2/cones/";
  cv::Mat l = cv::imread(dir + "imL.png", cv::IMREAD_GRAYSCALE);
  cv::Mat r = cv::imread(dir + "imR.png", cv::IMREAD_GRAYSCALE);
  if (l.empty() || r.empty()) {
    static bool told = false;
    if (!told)
      std::fprintf(stderr, "bench_stereo: %s absent, using a synthetic pair\n", dir.c_str());
    told = true;
    std::mt19937 rng(7);
    l.create(h, w, CV_8U);
    cv::randu(l, 0, 255);
    cv::GaussianBlur(l, l, cv::Size(5, 5), 1.2);
    r = cv::Mat::zeros(h, w, CV_8U);
    l.colRange(20, w).copyTo(r.colRange(0, w - 20));
  } else {
    cv::resize(l, l, cv::Size(w, h), 0, 0, cv::INTER_LINEAR);
    cv::resize(r, r, cv::Size(w, h), 0, 0, cv::INTER_LINEAR);
  }
  p.left = l;
  p.right = r;
  return cache.emplace(key, p).first->second;
}

svslam::ImageView<const std::uint8_t> view(const cv::Mat& m) {
  return {m.ptr<std::uint8_t>(), m.cols, m.rows, static_cast<std::ptrdiff_t>(m.step)};
}

void setCounters(benchmark::State& st, int w, int h, int ndisp) {
  const double px = static_cast<double>(w) * h;
  st.SetItemsProcessed(static_cast<std::int64_t>(st.iterations() * px));
  st.SetBytesProcessed(static_cast<std::int64_t>(st.iterations() * px * 2));
  st.counters["disparities"] = ndisp;
}

// Row stripes per thread of the two-thread cases (more stripes balance a noisy core's delay,
// each costs a warm-up of window_h cost rows); BM_SvslamStripes compares the choices.
constexpr int kStripesPerThread = 4;

void runSvslam(benchmark::State& st, svslam::MatchingCost cost, int per_thread) {
  const int w = static_cast<int>(st.range(0)), h = static_cast<int>(st.range(1));
  const int nd = static_cast<int>(st.range(2)), threads = static_cast<int>(st.range(3));
  const Pair& p = pairOfSize(w, h);
  svslam::DenseStereoParams params;
  params.cost = cost;
  params.max_disp = nd;
  if (cost == svslam::MatchingCost::kCensus) {
    params.census_w = 9;
    params.census_h = 7;
  } else {
    params.window_w = 9;
    params.window_h = 9;
  }
  params.lr_check = true;
  params.subpixel = true;
  params.num_stripes = threads == 1 ? 1 : per_thread * threads;
  svslam::DenseStereo stereo(params, w, h);
  if (!stereo.initStatus()) {
    st.SkipWithError(stereo.initStatus().message().c_str());
    return;
  }
  svslam::ThreadPoolExecutor ex(threads);
  svslam::DisparityResult out;
  for (auto _ : st) {
    auto s = stereo.process(view(p.left), view(p.right), out, ex);
    benchmark::DoNotOptimize(out.disparity_px.row(0));
    if (!s) st.SkipWithError(s.message().c_str());
  }
  setCounters(st, w, h, nd);
  st.counters["valid_fraction"] = out.stats.valid / (static_cast<double>(w) * h);
  st.SetLabel(out.stats.backend);
}

// args: width, height, disparities, threads
void BM_Svslam(benchmark::State& st, svslam::MatchingCost cost) {
  runSvslam(st, cost, kStripesPerThread);
}

// args: width, height, disparities, threads, stripes per thread (census 9x7)
void BM_SvslamStripes(benchmark::State& st) {
  runSvslam(st, svslam::MatchingCost::kCensus, static_cast<int>(st.range(4)));
}

void BM_OpenCvBM(benchmark::State& st) {
  const int w = static_cast<int>(st.range(0)), h = static_cast<int>(st.range(1));
  const int nd = static_cast<int>(st.range(2)), threads = static_cast<int>(st.range(3));
  const Pair& p = pairOfSize(w, h);
  cv::setNumThreads(threads);
  auto bm = cv::StereoBM::create(nd, 9);
  bm->setTextureThreshold(10);
  bm->setUniquenessRatio(10);
  bm->setDisp12MaxDiff(1);
  cv::Mat d;
  for (auto _ : st) {
    bm->compute(p.left, p.right, d);
    benchmark::DoNotOptimize(d.data);
  }
  setCounters(st, w, h, nd);
}

void BM_OpenCvSGBM(benchmark::State& st) {
  const int w = static_cast<int>(st.range(0)), h = static_cast<int>(st.range(1));
  const int nd = static_cast<int>(st.range(2)), threads = static_cast<int>(st.range(3));
  const Pair& p = pairOfSize(w, h);
  cv::setNumThreads(threads);
  auto sgbm = cv::StereoSGBM::create(0, nd, 5, 8 * 25, 32 * 25, 1, 63, 10, 100, 2,
                                     cv::StereoSGBM::MODE_SGBM_3WAY);
  cv::Mat d;
  for (auto _ : st) {
    sgbm->compute(p.left, p.right, d);
    benchmark::DoNotOptimize(d.data);
  }
  setCounters(st, w, h, nd);
}

void configs(benchmark::internal::Benchmark* b) {
  for (auto wh : {std::make_pair(640, 480), std::make_pair(1024, 768)})
    for (int nd : {64, 128})
      for (int t : {1, 2}) b->Args({wh.first, wh.second, nd, t});
  b->ArgNames({"w", "h", "ndisp", "threads"})->Unit(benchmark::kMillisecond)->UseRealTime();
}

BENCHMARK_CAPTURE(BM_Svslam, census9x7, svslam::MatchingCost::kCensus)->Apply(configs);
BENCHMARK_CAPTURE(BM_Svslam, sad9x9, svslam::MatchingCost::kSad)->Apply(configs);
BENCHMARK(BM_SvslamStripes)
    ->ArgsProduct({{1024}, {768}, {128}, {2}, {1, 2, 4, 8}})
    ->ArgNames({"W", "H", "ndisp", "threads", "stripes_per_thread"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_OpenCvBM)->Apply(configs);
BENCHMARK(BM_OpenCvSGBM)->Apply(configs);

// Collects real times by configuration to print svslam / OpenCV ratios at the end.
class RatioReporter : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    ConsoleReporter::ReportRuns(runs);
    for (const auto& r : runs) {
      if (r.run_type != Run::RT_Iteration || r.error_occurred) continue;
      const std::string name = r.benchmark_name();
      const auto slash = name.find("/w:");
      if (slash == std::string::npos) continue;
      times_[name.substr(slash)][name.substr(0, slash)] = r.GetAdjustedRealTime();
    }
  }
  void Finalize() override {
    ConsoleReporter::Finalize();
    std::printf("\nRatios (time of svslam / time of OpenCV, same images, same run):\n");
    for (const auto& [cfg, m] : times_) {
      auto get = [&](const char* k) {
        auto it = m.find(k);
        return it == m.end() ? NAN : it->second;
      };
      const double census = get("BM_Svslam/census9x7"), sad = get("BM_Svslam/sad9x9");
      const double bm = get("BM_OpenCvBM"), sgbm = get("BM_OpenCvSGBM");
      std::printf(
          "%-40s census/BM %.3f  census/SGBM %.3f  sad/BM %.3f  census %.2f ms  BM %.2f ms\n",
          cfg.c_str(), census / bm, census / sgbm, sad / bm, census, bm);
    }
  }

 private:
  std::map<std::string, std::map<std::string, double>> times_;
};

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  RatioReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  benchmark::Shutdown();
  return 0;
}
