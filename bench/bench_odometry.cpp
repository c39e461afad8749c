// Front end + visual motion estimation per frame, one thread, on KITTI frames (1226x370):
// svslam's StereoOdometry against an OpenCV reference doing the same job the usual way (ORB
// detect + describe on both images, brute-force Hamming stereo and temporal matching,
// solvePnPRansac). Image loading is excluded. Prints ms per frame and the ratio svslam / OpenCV
// of the same run, and the target (median <= 25 ms per frame).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>
#include <opencv2/calib3d.hpp>
#include <opencv2/features2d.hpp>
#include <string>
#include <vector>

#include "drivers/files/opencv_view.hpp"
#include "drivers/source/stereo_source.hpp"
#include "frame_reporter.hpp"
#include "motion/rotation_alignment.hpp"
#include "odometry/stereo_odometry.hpp"
#include "odometry/stereo_stage.hpp"

namespace {

const std::string kKitti = std::string(SVSLAM_DATA_DIR) + "/kitti_odometry_seq_a";
constexpr int kFrames = 20;

struct Sequence {
  svslam::StereoCalibration calib;
  std::vector<svslam::drivers::StereoFrame> frames;
  std::string error;
};

const Sequence& sequence() {
  static Sequence s = [] {
    Sequence q;
    auto src = svslam::drivers::openStereoSource("kitti:" + kKitti);
    if (!src) {
      q.error = src.status().message();
      return q;
    }
    q.calib = (*src)->calibration();
    for (int i = 0; i < kFrames; ++i) {
      svslam::drivers::StereoFrame f;
      auto more = (*src)->next(f);
      if (!more || !*more) break;
      q.frames.push_back(std::move(f));
    }
    return q;
  }();
  return s;
}

// The front end with the library defaults; `repredict` false leaves out the re-prediction of a
// poor temporal search (docs/odometry.md), `disparity_offset` false the online disparity offset,
// for the same-run cost of each.
void frontEnd(benchmark::State& st, bool repredict, bool disparity_offset = true) {
  const Sequence& seq = sequence();
  if (seq.frames.empty()) {
    st.SkipWithError(("no KITTI data: " + seq.error).c_str());
    return;
  }
  svslam::StereoOdometryParams params;
  params.repredict = repredict;
  params.ransac_on_repredict = repredict;
  params.disparity_offset.enabled = disparity_offset;
  svslam::StereoStage stage(params, seq.calib);
  svslam::StereoStageOutput stereo;
  svslam::StereoOdometry vo(params, seq.calib);
  svslam::SerialExecutor ex;
  svslam::OdometryFrameResult r;
  int tracked = 0;
  for (auto _ : st) {
    vo.resetTracking();
    for (const auto& f : seq.frames) {
      (void)stage.process(f.left.cview(), f.right.cview(), vo.feedback(), stereo, ex);
      (void)vo.process(f.left.cview(), stereo, r);
      tracked += r.tracked;
    }
  }
  st.counters["frames"] = static_cast<double>(seq.frames.size());
  st.counters["tracked_pct"] =
      100.0 * tracked / (static_cast<double>(st.iterations()) * static_cast<double>(seq.frames.size()));
  st.SetItemsProcessed(static_cast<std::int64_t>(st.iterations() * seq.frames.size()));
}

void BM_FrontEnd_svslam(benchmark::State& st) { frontEnd(st, true); }
void BM_FrontEnd_svslam_no_repredict(benchmark::State& st) { frontEnd(st, false); }
void BM_FrontEnd_svslam_no_disparity_offset(benchmark::State& st) { frontEnd(st, true, false); }

// One rotation alignment of the re-prediction (KITTI frames 0 and 2, the constant-velocity and
// the identity starts), the cost a re-predicted frame adds before its wide pass.
void BM_RotationAlignment(benchmark::State& st) {
  const Sequence& seq = sequence();
  if (seq.frames.size() < 3) {
    st.SkipWithError(("no KITTI data: " + seq.error).c_str());
    return;
  }
  const svslam::RotationAlignmentParams params;
  svslam::RotationAlignment align(params, seq.calib.width, seq.calib.height);
  const std::vector<Eigen::Matrix3d> starts = {Eigen::Matrix3d::Identity(),
                                               Eigen::Matrix3d::Identity()};
  svslam::RotationAlignmentResult out;
  for (auto _ : st) {
    (void)align.process(seq.frames[0].left.cview(), seq.frames[2].left.cview(),
                        seq.calib.leftCamera(), starts, out);
    benchmark::DoNotOptimize(out.R_cur_prev);
  }
}
BENCHMARK(BM_RotationAlignment)->Unit(benchmark::kMillisecond)->MinTime(1.0);

void BM_FrontEnd_opencv_orb(benchmark::State& st) {
  const Sequence& seq = sequence();
  if (seq.frames.empty()) {
    st.SkipWithError(("no KITTI data: " + seq.error).c_str());
    return;
  }
  cv::setNumThreads(1);
  auto orb = cv::ORB::create(1000);
  cv::BFMatcher bf(cv::NORM_HAMMING, true);
  const cv::Mat K = (cv::Mat_<double>(3, 3) << seq.calib.f_px, 0, seq.calib.cx_px, 0,
                     seq.calib.f_px, seq.calib.cy_px, 0, 0, 1);
  int tracked = 0;
  for (auto _ : st) {
    std::vector<cv::KeyPoint> prev_kp;
    cv::Mat prev_desc;
    std::vector<cv::Point3f> prev_xyz;
    for (const auto& f : seq.frames) {
      std::vector<cv::KeyPoint> kl, kr;
      cv::Mat dl, dr;
      orb->detectAndCompute(svslam::drivers::asMat(f.left), cv::noArray(), kl, dl);
      orb->detectAndCompute(svslam::drivers::asMat(f.right), cv::noArray(), kr, dr);
      std::vector<cv::DMatch> sm;
      if (!dl.empty() && !dr.empty()) bf.match(dl, dr, sm);
      // Stereo: same row (2 px), positive disparity -> 3D point.
      std::vector<cv::KeyPoint> kp;
      cv::Mat desc;
      std::vector<cv::Point3f> xyz;
      for (const auto& m : sm) {
        const auto& a = kl[static_cast<std::size_t>(m.queryIdx)].pt;
        const auto& b = kr[static_cast<std::size_t>(m.trainIdx)].pt;
        const float d = a.x - b.x;
        if (std::abs(a.y - b.y) > 2 || d < 1) continue;
        const double z = seq.calib.f_px * seq.calib.baseline_m / d;
        xyz.emplace_back(static_cast<float>((a.x - seq.calib.cx_px) * z / seq.calib.f_px),
                         static_cast<float>((a.y - seq.calib.cy_px) * z / seq.calib.f_px),
                         static_cast<float>(z));
        kp.push_back(kl[static_cast<std::size_t>(m.queryIdx)]);
        desc.push_back(dl.row(m.queryIdx));
      }
      if (!prev_desc.empty() && !desc.empty()) {
        std::vector<cv::DMatch> tm;
        bf.match(prev_desc, desc, tm);
        std::vector<cv::Point3f> obj;
        std::vector<cv::Point2f> img;
        for (const auto& m : tm) {
          obj.push_back(prev_xyz[static_cast<std::size_t>(m.queryIdx)]);
          img.push_back(kp[static_cast<std::size_t>(m.trainIdx)].pt);
        }
        cv::Mat rvec, tvec;
        if (obj.size() >= 6 &&
            cv::solvePnPRansac(obj, img, K, cv::noArray(), rvec, tvec, false, 100, 2.0))
          ++tracked;
      }
      prev_kp = kp;
      prev_desc = desc;
      prev_xyz = xyz;
    }
  }
  st.counters["frames"] = static_cast<double>(seq.frames.size());
  st.counters["tracked_pct"] = 100.0 * tracked /
                               (static_cast<double>(st.iterations()) *
                                static_cast<double>(seq.frames.size() - 1));
  st.SetItemsProcessed(static_cast<std::int64_t>(st.iterations() * seq.frames.size()));
}

BENCHMARK(BM_FrontEnd_svslam)->Unit(benchmark::kMillisecond)->MinTime(2.0);
BENCHMARK(BM_FrontEnd_svslam_no_repredict)->Unit(benchmark::kMillisecond)->MinTime(2.0);
BENCHMARK(BM_FrontEnd_svslam_no_disparity_offset)->Unit(benchmark::kMillisecond)->MinTime(2.0);
BENCHMARK(BM_FrontEnd_opencv_orb)->Unit(benchmark::kMillisecond)->MinTime(2.0);

// Prints per-frame times and the ratio svslam / OpenCV at the end.
class FrameReporter : public svslam::bench::FrameReporter {
 public:
  FrameReporter() : svslam::bench::FrameReporter(Frames::kPerIteration) {}
  void Finalize() override {
    ConsoleReporter::Finalize();
    const auto a = per_frame_ms_.find("BM_FrontEnd_svslam/min_time:2.000");
    const auto b = per_frame_ms_.find("BM_FrontEnd_opencv_orb/min_time:2.000");
    std::printf("\nPer frame (front end + motion, 1 thread, KITTI 1226x370):\n");
    for (const auto& [name, ms] : per_frame_ms_) std::printf("  %-40s %8.2f ms\n", name.c_str(), ms);
    if (a != per_frame_ms_.end())
      std::printf("  svslam target: <= 25 ms per frame -> %s\n", a->second <= 25 ? "met" : "NOT met");
    if (a != per_frame_ms_.end() && b != per_frame_ms_.end())
      std::printf("  ratio svslam / OpenCV ORB reference: %.2f\n", a->second / b->second);
  }
};

}  // namespace

int main(int argc, char** argv) { return svslam::bench::benchmarkMain<FrameReporter>(argc, argv); }
