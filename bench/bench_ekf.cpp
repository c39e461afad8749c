// EKF SLAM frame cost (seed 001 sec. 4, issue 4 target: <= 5 ms per frame with 300 landmarks):
// one prediction + one update with 20, 30 or 40 stereo observations, 300 landmarks in the
// state (batches of 16 observations, the default), svslam's sparse-H update (Joseph form, and the
// optimal-gain form) beside a naive dense textbook EKF (full F, dense H,
// P = (I - K H) P (I - K H)^T + K R K^T) in the same binary. One thread, except
// joseph_2threads: the update's products split in row pieces on a two-thread pool
// (bit-identical results). BM_Ekf_svslam_default: the SLAM's default configuration (140
// landmarks, up to 60 observations a frame, batches of 16; EkfSlamParams{}) with 30, 60 and 100
// observations; BM_Ekf_svslam_default_bearings: the same with the observations as bearings
// (2 rows each instead of 3). Also the n x n product alone per matrix backend beside Eigen's.
// Prints ms per frame and the ratio svslam / dense at the end.
#include <benchmark/benchmark.h>

#include <Eigen/Cholesky>
#include <cstdio>
#include <map>
#include <random>
#include <string>

#include "frame_reporter.hpp"
#include "motion/visual_motion.hpp"
#include "pipeline/thread_pool_executor.hpp"
#include "simd/matrix_kernels.hpp"
#include "slam/ekf_slam.hpp"
#include "slam/pose_jacobians.hpp"

namespace {

using svslam::Matrix6d;
using svslam::Vector6d;
constexpr int kLandmarks = 300;

// Stereo-like covariance (f = 700 px, b = 0.5 m, 0.5 px image plane, 0.3 px disparity):
// lateral sigma z * 0.5 / f, depth sigma z^2 * 0.3 / (f b).
Eigen::Matrix3d stereoCov(const Eigen::Vector3d& p) {
  const double s_lat = p.z() * 0.5 / 700.0, s_z = p.z() * p.z() * 0.3 / 350.0;
  return Eigen::Vector3d(s_lat * s_lat, s_lat * s_lat, s_z * s_z).asDiagonal();
}

Matrix6d motionCov() {
  return (Vector6d() << 4e-6, 4e-6, 1e-6, 4e-4, 4e-4, 1e-4).finished().asDiagonal();
}

Eigen::Isometry3d motion() {
  Eigen::Isometry3d u = Eigen::Isometry3d::Identity();
  u.linear() = svslam::expSO3(Eigen::Vector3d(0.001, -0.002, 0.001));
  u.translation() = Eigen::Vector3d(0.02, 0.0, -0.05);
  return u;
}

// `count` landmarks spread in front of the camera, initialised with stereo covariances.
std::vector<Eigen::Vector3d> scene(int count = kLandmarks) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> x(-15, 15), y(-8, 8), z(5, 40);
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i < count; ++i) pts.emplace_back(x(rng), y(rng), z(rng));
  return pts;
}

// The 300-landmark configuration of the target: the default filter (batches of 16
// observations) with room for 300 landmarks.
svslam::EkfSlamParams params300() {
  svslam::EkfSlamParams p;
  p.max_landmarks = kLandmarks;
  return p;
}

// Observations of n_obs landmarks (rotating through the state) at their predicted position
// plus a small offset, so that gating keeps them.
void observe(const svslam::EkfSlam& ekf, int n_obs, int frame,
             std::vector<svslam::LandmarkObservation>& obs) {
  obs.clear();
  const auto& ids = ekf.landmarkIds();
  for (int j = 0; j < n_obs; ++j) {
    const int id = ids[static_cast<std::size_t>(frame * 7 + j * 11) % ids.size()];
    Eigen::Vector3d m;
    Eigen::Matrix3d C;
    (void)ekf.landmark(id, m, C);
    const Eigen::Vector3d z = svslam::observeLandmark(ekf.pose(), m);
    obs.push_back({id, z + 1e-3 * Eigen::Vector3d(1, -1, 2), stereoCov(z)});
  }
}

// The same observations as bearings (normalised image coordinates, 0.5 px at f = 700 px).
void toBearings(const std::vector<svslam::LandmarkObservation>& obs,
                std::vector<svslam::BearingObservation>& bearings) {
  bearings.clear();
  const double s = 0.5 / 700.0;
  for (const auto& o : obs)
    bearings.push_back({o.id, o.z_cam.head<2>() / o.z_cam.z(), s * s * Eigen::Matrix2d::Identity()});
}

void runSvslam(benchmark::State& st, bool joseph, int threads = 1,
               svslam::EkfSlamParams params = params300(), bool bearings = false) {
  const int n_obs = static_cast<int>(st.range(0));
  svslam::ThreadPoolExecutor pool(threads);
  params.joseph_form = joseph;
  svslam::EkfSlam ekf(params);
  (void)ekf.reset(Eigen::Isometry3d::Identity(), motionCov());
  for (const auto& p : scene(params.max_landmarks)) (void)ekf.addLandmark(p, stereoCov(p));
  std::vector<svslam::LandmarkObservation> obs;
  std::vector<svslam::BearingObservation> bobs;
  std::vector<svslam::ObservationResult> res;
  int frame = 0, accepted = 0;
  for (auto _ : st) {
    st.PauseTiming();
    observe(ekf, n_obs, frame++, obs);
    if (bearings) toBearings(obs, bobs);
    st.ResumeTiming();
    svslam::Executor* ex = threads > 1 ? &pool : nullptr;
    if (!ekf.predict(motion(), motionCov()) ||
        !(bearings ? ekf.updateBearings(bobs, res, ex) : ekf.update(obs, res, ex)))
      st.SkipWithError("EKF failed");
    for (const auto& r : res) accepted += r.accepted ? 1 : 0;
  }
  st.counters["frames"] = benchmark::Counter(static_cast<double>(st.iterations()));
  st.counters["accepted_per_frame"] =
      static_cast<double>(accepted) / static_cast<double>(st.iterations());
}

void BM_Ekf_svslam_joseph(benchmark::State& st) { runSvslam(st, true); }
void BM_Ekf_svslam_optimal_gain(benchmark::State& st) { runSvslam(st, false); }
void BM_Ekf_svslam_joseph_2threads(benchmark::State& st) { runSvslam(st, true, 2); }
void BM_Ekf_svslam_default(benchmark::State& st) {
  runSvslam(st, true, 1, svslam::EkfSlamParams{});
}
// The default filter observing the same landmarks by bearing (camera loss, --mode mono).
void BM_Ekf_svslam_default_bearings(benchmark::State& st) {
  runSvslam(st, true, 1, svslam::EkfSlamParams{}, true);
}

// Naive dense EKF on the same model: full n x n Jacobians and products everywhere.
void BM_Ekf_dense_reference(benchmark::State& st) {
  const int n_obs = static_cast<int>(st.range(0)), n = 6 + 3 * kLandmarks, m = 3 * n_obs;
  svslam::EkfSlam init(params300());  // same initial state as the svslam runs
  (void)init.reset(Eigen::Isometry3d::Identity(), motionCov());
  for (const auto& p : scene()) (void)init.addLandmark(p, stereoCov(p));
  Eigen::Isometry3d T = init.pose();
  Eigen::MatrixXd P = init.covariance();
  Eigen::VectorXd lm(3 * kLandmarks);
  for (int i = 0; i < kLandmarks; ++i) {
    Eigen::Vector3d p;
    Eigen::Matrix3d C;
    (void)init.landmark(init.landmarkIds()[static_cast<std::size_t>(i)], p, C);
    lm.segment<3>(3 * i) = p;
  }
  std::vector<svslam::LandmarkObservation> obs;
  int frame = 0;
  for (auto _ : st) {
    st.PauseTiming();
    observe(init, n_obs, frame++, obs);  // ids = slots of `init`, which never changes order
    st.ResumeTiming();
    Matrix6d F_x, F_u;
    svslam::predictionJacobians(T, motion(), F_x, F_u);
    Eigen::MatrixXd F = Eigen::MatrixXd::Identity(n, n), G = Eigen::MatrixXd::Zero(n, 6);
    F.topLeftCorner<6, 6>() = F_x;
    G.topRows<6>() = F_u;
    P = F * P * F.transpose() + G * motionCov() * G.transpose();
    T = svslam::predictPose(T, motion());
    Eigen::MatrixXd H = Eigen::MatrixXd::Zero(m, n), R = Eigen::MatrixXd::Zero(m, m);
    Eigen::VectorXd nu(m);
    for (int j = 0; j < n_obs; ++j) {
      const int s = obs[static_cast<std::size_t>(j)].id;  // ids 0..299 = slots in `init`
      svslam::Matrix36d H_p;
      Eigen::Matrix3d H_m;
      svslam::observationJacobians(T, lm.segment<3>(3 * s), H_p, H_m);
      H.block<3, 6>(3 * j, 0) = H_p;
      H.block<3, 3>(3 * j, 6 + 3 * s) = H_m;
      R.block<3, 3>(3 * j, 3 * j) = obs[static_cast<std::size_t>(j)].R;
      nu.segment<3>(3 * j) = 1e-3 * Eigen::Vector3d(1, -1, 2);
    }
    const Eigen::MatrixXd S = H * P * H.transpose() + R;
    const Eigen::MatrixXd K = P * H.transpose() * S.llt().solve(Eigen::MatrixXd::Identity(m, m));
    const Eigen::MatrixXd IKH = Eigen::MatrixXd::Identity(n, n) - K * H;
    P = IKH * P * IKH.transpose() + K * R * K.transpose();
    const Eigen::VectorXd dx = K * nu;
    T = svslam::boxPlus(T, dx.head<6>());
    lm += dx.tail(n - 6);
    benchmark::DoNotOptimize(P.data());
  }
  st.counters["frames"] = benchmark::Counter(static_cast<double>(st.iterations()));
}

// The update's n x n product alone: lower triangle of P - U V^T with n = 906 (300 landmarks)
// and r = 2m = 180 (Joseph form, 30 observations), per matrix backend beside Eigen's
// triangular product (the previous implementation) on the same operands.
void runRankUpdate(benchmark::State& st, int backend) {
  const int n = 6 + 3 * kLandmarks, r = 180;
  std::mt19937 rng(3);
  std::normal_distribution<double> g;
  Eigen::MatrixXd P(n, n), U(n, r), V(n, r);
  for (Eigen::MatrixXd* M : {&P, &U, &V})
    for (Eigen::Index i = 0; i < M->size(); ++i) M->data()[i] = g(rng);
  std::vector<double> ws(svslam::simd::rankUpdateWorkspace(n, n, r));
  const svslam::simd::MatrixKernels* k = nullptr;
  if (backend >= 0) {
    const auto b = static_cast<svslam::simd::Backend>(backend);
    if (!svslam::simd::matrixBackendAvailable(b)) {
      st.SkipWithError("backend not available on this CPU");
      return;
    }
    k = &svslam::simd::matrixKernels(b);
  }
  for (auto _ : st) {
    if (k)
      k->rankUpdate(P.data(), n, U.data(), n, V.data(), n, n, n, r, true, 0, ws.data());
    else
      P.triangularView<Eigen::Lower>() -= U * V.transpose();
    benchmark::DoNotOptimize(P.data());
  }
  st.counters["GFMA/s"] = benchmark::Counter(0.5 * n * (n + 1.0) * r * 1e-9,
                                             benchmark::Counter::kIsIterationInvariantRate);
}
void BM_RankUpdate_eigen(benchmark::State& st) { runRankUpdate(st, -1); }
void BM_RankUpdate_scalar(benchmark::State& st) {
  runRankUpdate(st, static_cast<int>(svslam::simd::Backend::kScalar));
}
void BM_RankUpdate_avx2(benchmark::State& st) {
  runRankUpdate(st, static_cast<int>(svslam::simd::Backend::kAvx2));
}
void BM_RankUpdate_neon(benchmark::State& st) {
  runRankUpdate(st, static_cast<int>(svslam::simd::Backend::kNeon));
}
BENCHMARK(BM_RankUpdate_eigen)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RankUpdate_scalar)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_RankUpdate_avx2)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RankUpdate_neon)->Unit(benchmark::kMillisecond);

BENCHMARK(BM_Ekf_svslam_joseph)
    ->Arg(20)
    ->Arg(30)
    ->Arg(40)
    ->Unit(benchmark::kMillisecond)
    ->MinTime(1.0);
BENCHMARK(BM_Ekf_svslam_joseph_2threads)
    ->Arg(20)
    ->Arg(30)
    ->Arg(40)
    ->Unit(benchmark::kMillisecond)
    ->MinTime(1.0);
BENCHMARK(BM_Ekf_svslam_optimal_gain)
    ->Arg(20)
    ->Arg(30)
    ->Arg(40)
    ->Unit(benchmark::kMillisecond)
    ->MinTime(1.0);
BENCHMARK(BM_Ekf_svslam_default)
    ->Arg(30)
    ->Arg(60)
    ->Arg(100)
    ->Unit(benchmark::kMillisecond)
    ->MinTime(1.0);
BENCHMARK(BM_Ekf_svslam_default_bearings)
    ->Arg(30)
    ->Arg(60)
    ->Arg(100)
    ->Unit(benchmark::kMillisecond)
    ->MinTime(1.0);
BENCHMARK(BM_Ekf_dense_reference)->Arg(30)->Unit(benchmark::kMillisecond)->Iterations(5);

// Prints ms per frame and the ratios svslam / dense reference at the end.
class FrameReporter : public svslam::bench::FrameReporter {
 public:
  FrameReporter() : svslam::bench::FrameReporter(Frames::kOnePerIteration) {}
  void Finalize() override {
    ConsoleReporter::Finalize();
    std::printf(
        "\nPer frame (predict + update; %d landmarks in the state, %d in svslam_default):\n",
        kLandmarks, svslam::EkfSlamParams{}.max_landmarks);
    for (const auto& [name, ms] : per_frame_ms_)
      std::printf("  %-52s %8.2f ms\n", name.c_str(), ms);
    double dense = 0;
    for (const auto& [name, ms] : per_frame_ms_)
      if (name.find("dense_reference/30") != std::string::npos) dense = ms;
    for (const auto& [name, ms] : per_frame_ms_) {
      const bool is_default = name.find("svslam_default") != std::string::npos;
      if (name.find("svslam") == std::string::npos ||
          (!is_default && name.find("/30") == std::string::npos))
        continue;
      std::printf("  %s: target <= 5 ms per frame -> %s", name.c_str(),
                  ms <= 5 ? "met" : "NOT met");
      if (dense > 0 && !is_default)
        std::printf("; ratio svslam / dense reference: %.4f", ms / dense);
      std::printf("\n");
    }
  }
};

}  // namespace

int main(int argc, char** argv) { return svslam::bench::benchmarkMain<FrameReporter>(argc, argv); }
