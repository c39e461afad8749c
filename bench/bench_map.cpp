// Elevation-map fusion cost per frame, one thread: map::DemFuser::process on a 1024x768 frame
// whose EVERY pixel is a valid dense point (786432 points), beside a plain per-point reference in
// the same run. Input: frames 0..9 of the default synthetic flight (blimp, looking down), the
// exact disparity of every pixel (trueDisparity), sigma_d = 0.2 px everywhere, the true pose
// relative to frame 0 (T_world_cam = pose(0)^-1 pose(k)), pose_cov = diag(1e-6 rad^2 x3,
// 1e-4 m^2 x3), R_map_world from the true gravity in the first camera (mapRotationFromGravity).
// Rendering is excluded.
//
// Each benchmark first warms its own map on the 10 frames (every tile exists, every cell has an
// estimate, so the fuser's gate is exercised), then every repetition (1 iteration) fuses the next
// frame, cycling through the 10; the time is the wall time of that one call (manual time).
//   BM_DemFuser                 DemFuser::process: points in float, pose variance, gate, summed
//                               per cell, then one DemMap::fuse per touched cell.
//   BM_PlainPerPointReference   the straightforward way: for every pixel, back-project in double,
//                               Eigen::Isometry3d to the map, floor to the cell, and one
//                               DemMap::fuse per point (CellMeasurement: sum_w = 1/var_indep,
//                               sum_wh, count 1, luminance); no pose variance, no gating, no
//                               per-frame accumulation.
//
// How to read it: the rows ..._p50 and ..._p99 (custom statistics over the 100 repetitions, plus
// the library's mean/median/stddev) give ms per frame; counters: points = points per frame,
// ns_per_point = time / points, cells = map cells updated (fuser only).
//   Target (seed 001 sec 5.2): BM_DemFuser p99 <= 20 ms per frame on one core.
//   Ratio: BM_DemFuser p50 / BM_PlainPerPointReference p50 (and the same for p99), both of the
//   same run; < 1 means the fuser beats the plain per-point way.
// Run: build/bench/bench_map   (repetitions are fixed by the benchmark; --benchmark_min_time is
// ignored because each repetition is one iteration).
#include <benchmark/benchmark.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "drivers/synthetic/synthetic_flight.hpp"
#include "map/dem_fuser.hpp"
#include "map/dem_map.hpp"
#include "map/dem_params.hpp"
#include "map/map_frame.hpp"
#include "stereo/dense_stereo.hpp"

namespace {

using svslam::map::CellMeasurement;
using svslam::map::DemFrame;
using svslam::map::DemFuser;
using svslam::map::DemFuseStats;
using svslam::map::DemMap;
using svslam::map::DemParams;

constexpr int kFrames = 10;
constexpr int kRepetitions = 100;
constexpr float kSigmaD = 0.2f;

struct Frame {
  svslam::ImageU8 left;
  svslam::DisparityResult disparity;
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();
  std::int64_t t_ns = 0;
  int points = 0;  // pixels with a valid disparity (all of them expected)
};

struct Inputs {
  svslam::StereoCalibration calib;
  Eigen::Matrix3d R_map_world = Eigen::Matrix3d::Identity();
  Eigen::Matrix<double, 6, 6> pose_cov = Eigen::Matrix<double, 6, 6>::Zero();
  std::vector<Frame> frames;
  std::string error;
};

const Inputs& inputs() {
  static const Inputs in = [] {
    Inputs q;
    const svslam::drivers::SyntheticFlightParams fp;  // default flight: blimp, 1024x768
    auto flight_or = svslam::drivers::SyntheticFlight::create(fp);
    if (!flight_or) {
      q.error = "synthetic flight: " + flight_or.status().message();
      return q;
    }
    const svslam::drivers::SyntheticFlight& flight = *flight_or;
    q.calib = flight.calibration();
    // Gravity (world -z) in the first left camera's frame -> R_map_world.
    const Eigen::Vector3d g = flight.pose(0).linear().transpose() * Eigen::Vector3d(0, 0, -1);
    const svslam::Status rs =
        svslam::map::mapRotationFromGravity({g.x(), g.y(), g.z()}, q.R_map_world);
    if (!rs) {
      q.error = "mapRotationFromGravity: " + rs.message();
      return q;
    }
    q.pose_cov.diagonal() << 1e-6, 1e-6, 1e-6, 1e-4, 1e-4, 1e-4;
    const Eigen::Isometry3d T0_inv = flight.pose(0).inverse();
    svslam::ImageU8 right;
    for (int k = 0; k < kFrames; ++k) {
      Frame f;
      svslam::Status s = flight.render(k, f.left, right);
      if (s) s = flight.trueDisparity(k, f.disparity.disparity_px);
      if (!s) {
        q.error = "render frame " + std::to_string(k) + ": " + s.message();
        return q;
      }
      const int w = f.disparity.disparity_px.width(), h = f.disparity.disparity_px.height();
      f.disparity.sigma_d_px.resize(w, h);
      f.disparity.sigma_d_px.fill(kSigmaD);
      for (int v = 0; v < h; ++v) {
        const float* d = f.disparity.disparity_px.row(v);
        for (int x = 0; x < w; ++x) f.points += (d[x] > 0.0f && std::isfinite(d[x])) ? 1 : 0;
      }
      f.T_world_cam = T0_inv * flight.pose(k);
      f.t_ns = flight.timeNs(k);
      q.frames.push_back(std::move(f));
    }
    return q;
  }();
  return in;
}

// p-th percentile (nearest rank) of the repetitions' values.
double percentile(const std::vector<double>& v, double p) {
  if (v.empty()) return 0.0;
  std::vector<double> s(v);
  std::sort(s.begin(), s.end());
  const auto rank = static_cast<std::size_t>(std::ceil(p / 100.0 * static_cast<double>(s.size())));
  return s[std::min(s.size() - 1, rank > 0 ? rank - 1 : 0)];
}

using Clock = std::chrono::steady_clock;

// ---------------------------------------------------------------------------------------------
struct FuserState {
  DemParams params;
  DemMap map{params};
  DemFuser fuser;
  DemFuseStats stats;
  int next = 0;
  std::string error;
  explicit FuserState(const Inputs& in) : fuser(params, in.calib, in.R_map_world) {
    if (!fuser.initStatus()) error = "fuser: " + fuser.initStatus().message();
  }
  svslam::Status fuse(const Inputs& in, const Frame& f) {
    DemFrame df;
    df.left = f.left.cview();
    df.disparity = &f.disparity;
    df.T_world_cam = f.T_world_cam;
    df.pose_cov = in.pose_cov;
    df.t_ns = f.t_ns;
    return fuser.process(df, map, stats);
  }
};

void BM_DemFuser(benchmark::State& st) {
  const Inputs& in = inputs();
  if (!in.error.empty()) {
    st.SkipWithError(in.error.c_str());
    return;
  }
  static FuserState s = [&] {
    FuserState w(in);
    if (w.error.empty())
      for (const Frame& f : in.frames) (void)w.fuse(in, f);  // warm: tiles and cells exist
    return w;
  }();
  if (!s.error.empty()) {
    st.SkipWithError(s.error.c_str());
    return;
  }
  double ns = 0.0;
  int points = 0, cells = 0;
  for (auto _ : st) {
    const Frame& f = in.frames[static_cast<std::size_t>(s.next)];
    s.next = (s.next + 1) % kFrames;
    const auto t0 = Clock::now();
    const svslam::Status r = s.fuse(in, f);
    const auto t1 = Clock::now();
    if (!r) {
      st.SkipWithError(("process: " + r.message()).c_str());
      return;
    }
    if (s.stats.points_fused != f.points) {
      st.SkipWithError(("fused " + std::to_string(s.stats.points_fused) + " of " +
                        std::to_string(f.points) + " points")
                           .c_str());
      return;
    }
    const double dt = std::chrono::duration<double>(t1 - t0).count();
    st.SetIterationTime(dt);
    ns += dt * 1e9;
    points += s.stats.points_fused;
    cells += s.stats.cells_updated;
  }
  const auto it = static_cast<double>(st.iterations());
  st.counters["points"] = points / it;
  st.counters["cells"] = cells / it;
  st.counters["ns_per_point"] = points > 0 ? ns / points : 0.0;
}

// ---------------------------------------------------------------------------------------------
struct ReferenceState {
  DemParams params;
  DemMap map{params};
  std::int64_t seq = 0;
  int next = 0;
  // Fuses every point of f alone; returns the points fused.
  int fuse(const Inputs& in, const Frame& f) {
    const svslam::StereoCalibration& c = in.calib;
    Eigen::Isometry3d T_map_cam = Eigen::Isometry3d::Identity();
    T_map_cam.linear() = in.R_map_world;
    T_map_cam = T_map_cam * f.T_world_cam;
    const double tz = T_map_cam.translation().z();
    const double cell = params.cell_m;
    const std::int64_t s = seq++;
    int n = 0;
    for (int v = 0; v < c.height; ++v) {
      const float* d_row = f.disparity.disparity_px.row(v);
      const float* s_row = f.disparity.sigma_d_px.row(v);
      const std::uint8_t* g_row = f.left.row(v);
      for (int u = 0; u < c.width; ++u) {
        const double d = d_row[u];
        if (!(d > 0.0) || !std::isfinite(d)) continue;
        const double k = c.baseline_m / d;
        const Eigen::Vector3d X((u - c.cx_px) * k, (v - c.cy_px) * k, c.f_px * k);
        const Eigen::Vector3d p = T_map_cam * X;
        const double dh = (p.z() - tz) / d;  // (r_z . X_cam) / d
        const double sd = s_row[u];
        const double var = std::max(1e-10, dh * dh * sd * sd);
        CellMeasurement m;
        m.sum_w = 1.0 / var;
        m.sum_wh = p.z() / var;
        m.count = 1;
        m.sum_luminance = g_row[u];
        const int i = static_cast<int>(std::floor(p.x() / cell));
        const int j = static_cast<int>(std::floor(p.y() / cell));
        n += map.fuse(i, j, m, s, f.t_ns) ? 1 : 0;
      }
    }
    return n;
  }
};

void BM_PlainPerPointReference(benchmark::State& st) {
  const Inputs& in = inputs();
  if (!in.error.empty()) {
    st.SkipWithError(in.error.c_str());
    return;
  }
  static ReferenceState s = [&] {
    ReferenceState w;
    for (const Frame& f : in.frames) (void)w.fuse(in, f);  // warm: tiles and cells exist
    return w;
  }();
  double ns = 0.0;
  int points = 0;
  for (auto _ : st) {
    const Frame& f = in.frames[static_cast<std::size_t>(s.next)];
    s.next = (s.next + 1) % kFrames;
    const auto t0 = Clock::now();
    const int n = s.fuse(in, f);
    const auto t1 = Clock::now();
    benchmark::DoNotOptimize(n);
    if (n != f.points) {
      st.SkipWithError(("fused " + std::to_string(n) + " of " + std::to_string(f.points) +
                        " points")
                           .c_str());
      return;
    }
    const double dt = std::chrono::duration<double>(t1 - t0).count();
    st.SetIterationTime(dt);
    ns += dt * 1e9;
    points += n;
  }
  const auto it = static_cast<double>(st.iterations());
  st.counters["points"] = points / it;
  st.counters["ns_per_point"] = points > 0 ? ns / points : 0.0;
}

void configure(benchmark::internal::Benchmark* b) {
  b->Unit(benchmark::kMillisecond)
      ->UseManualTime()
      ->Iterations(1)
      ->Repetitions(kRepetitions)
      ->ComputeStatistics("p50", [](const std::vector<double>& v) { return percentile(v, 50); })
      ->ComputeStatistics("p99", [](const std::vector<double>& v) { return percentile(v, 99); })
      ->ReportAggregatesOnly(true);
}

}  // namespace

BENCHMARK(BM_DemFuser)->Apply(configure);
BENCHMARK(BM_PlainPerPointReference)->Apply(configure);

BENCHMARK_MAIN();
