// Loop-closing back end: pose-graph optimisation (loop/pose_graph.hpp, Ceres, one thread) of
// 1 000 and 5 000 keyframes on a circle driven in laps of 200 keyframes, noisy odometry edges and
// one loop edge per 100 keyframes (~1 %), started from the integrated odometry; and pairwise
// consistency maximisation (loop/loop_consistency.hpp) of 20 and 60 loop candidates (a quarter
// of them outliers) on a 1 000-keyframe drifting chain. Synthetic, seeded: needs no data.
#include <benchmark/benchmark.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "loop/loop_consistency.hpp"
#include "loop/pose_graph.hpp"
#include "motion/visual_motion.hpp"

namespace {

using svslam::Matrix6d;
using svslam::Vector6d;
constexpr int kPerLap = 200;

Matrix6d diagCov(double sigma_rot_rad, double sigma_trans_m) {
  Vector6d v;
  v << Eigen::Vector3d::Constant(sigma_rot_rad * sigma_rot_rad),
      Eigen::Vector3d::Constant(sigma_trans_m * sigma_trans_m);
  return v.asDiagonal();
}

Vector6d sampleNoise(const Matrix6d& C, std::mt19937& rng) {
  std::normal_distribution<double> n(0, 1);
  Vector6d z;
  for (int i = 0; i < 6; ++i) z[i] = n(rng);
  return Matrix6d(C.llt().matrixL()) * z;
}

Eigen::Isometry3d circlePose(int k) {
  const double a = 2 * M_PI * k / kPerLap;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(40 * std::cos(a), 40 * std::sin(a), 0.5 * std::sin(3 * a));
  T.linear() = svslam::expSO3(Eigen::Vector3d(0, 0, a + M_PI / 2)) *
               svslam::expSO3(Eigen::Vector3d(0.05 * std::sin(2 * a), 0.03 * std::cos(5 * a), 0));
  return T;
}

struct Graph {
  std::vector<Eigen::Isometry3d> truth, odometry;
  std::vector<Matrix6d> odo_cov;
  std::vector<svslam::PoseGraphEdge> edges;
};

// A circle flown lap after lap (kPerLap keyframes a lap), odometry with noise, and `loops` loop
// edges spread evenly over the laps after the first, each to the same place one lap earlier.
Graph makeGraph(int keyframes, int loops) {
  std::mt19937 rng(17);
  const Matrix6d Co = diagCov(0.002, 0.01), Cl = diagCov(0.001, 0.02);
  Graph g;
  for (int k = 0; k < keyframes; ++k) g.truth.push_back(circlePose(k));
  g.odometry.push_back(g.truth[0]);
  for (int k = 0; k + 1 < keyframes; ++k) {
    const Eigen::Isometry3d Z =
        svslam::boxPlus(g.truth[k].inverse() * g.truth[k + 1], sampleNoise(Co, rng));
    g.edges.push_back({k, k + 1, Z, Co, false});
    g.odo_cov.push_back(Co);
    g.odometry.push_back(g.odometry.back() * Z);
  }
  const int first = kPerLap + 37;
  const int step = std::max(1, (keyframes - first) / std::max(1, loops));
  for (int k = first, n = 0; k < keyframes && n < loops; k += step, ++n) {
    const int to = k - kPerLap;
    const Eigen::Isometry3d Z =
        svslam::boxPlus(g.truth[k].inverse() * g.truth[to], sampleNoise(Cl, rng));
    g.edges.push_back({k, to, Z, Cl, true});
  }
  return g;
}

void BM_PoseGraph(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const Graph g = makeGraph(n, static_cast<int>(state.range(1)));
  // Third argument: the window (LoopCloserParams::max_solve_keyframes), 0 = the whole graph.
  const int window = static_cast<int>(state.range(2));
  const int first_free = window > 0 ? std::max(0, n - window) : 0;
  svslam::PoseGraph graph(svslam::PoseGraphParams{});
  svslam::PoseGraphReport report;
  for (auto _ : state) {
    state.PauseTiming();
    std::vector<Eigen::Isometry3d> T = g.odometry;
    state.ResumeTiming();
    if (!graph.optimize(T, g.edges, 0, report, first_free)) state.SkipWithError("optimize failed");
    benchmark::DoNotOptimize(T.data());
  }
  state.counters["edges"] = static_cast<double>(g.edges.size());
  state.counters["iterations"] = report.iterations;
  state.counters["cost_ratio"] = report.final_cost / report.initial_cost;
}
// {keyframes, loop edges, window}: the 2 000 nodes with 50 loops, 1 000 / 5 000
// keyframes with a loop every 100 keyframes, and a 3-hour flight's 100 000 keyframes (1 000
// loops) solved in the default window of the newest 2 000 (loop.max_solve_keyframes).
BENCHMARK(BM_PoseGraph)
    ->Args({1000, 8, 0})
    ->Args({2000, 50, 0})
    ->Args({5000, 48, 0})
    ->Args({5000, 48, 2000})
    ->Args({100000, 1000, 2000})
    ->Unit(benchmark::kMillisecond);

void BM_LoopConsistency(benchmark::State& state) {
  const int candidates = static_cast<int>(state.range(0));
  const Graph g = makeGraph(1000, 8);
  std::mt19937 rng(23);
  const Matrix6d Cl = diagCov(0.001, 0.02);
  std::uniform_int_distribution<int> kf(kPerLap, 999);
  std::vector<svslam::LoopCandidateEdge> loops;
  for (int i = 0; i < candidates; ++i) {
    const int from = kf(rng);
    const int to = from - kPerLap * (1 + i % (from / kPerLap));  // 1 .. (laps so far) laps back
    Eigen::Isometry3d Z = g.truth[from].inverse() * g.truth[to];
    if (i % 4 == 3) Z.translation() += Eigen::Vector3d(2.0, -1.0, 0.5);  // outlier
    loops.push_back({from, to, svslam::boxPlus(Z, sampleNoise(Cl, rng)), Cl});
  }
  svslam::LoopConsistency pcm(svslam::LoopConsistencyParams{});
  svslam::LoopConsistencyResult out;
  for (auto _ : state) {
    if (!pcm.process(g.odometry, g.odo_cov, loops, out)) state.SkipWithError("process failed");
    benchmark::DoNotOptimize(out.clique.data());
  }
  int accepted_outliers = 0;
  for (const int i : out.clique) accepted_outliers += i % 4 == 3 ? 1 : 0;
  state.counters["inliers_kept"] = static_cast<double>(out.clique.size()) - accepted_outliers;
  state.counters["outliers_kept"] = accepted_outliers;
}
BENCHMARK(BM_LoopConsistency)->Arg(20)->Arg(60)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
