// The right camera unplugged mid-run, through the V4L2 layer (the fake driver of
// tests/drivers/camera): two fake cameras play the rendered synthetic flight (320 x 240), the
// right one leaves the bus after frame 14 and never comes back. With right_loss=left_only the
// source goes on with the left camera (frames with an empty right view), the stereo stage
// detects corners only, the EKF flies on bearings (SlamSystem's camera loss) from the first
// frame without the right image: a finite pose at every frame, the counters say what happened.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <opencv2/core.hpp>

#include "drivers/camera/v4l2_source.hpp"
#include "drivers/files/trajectory_io.hpp"
#include "drivers/source/stereo_source.hpp"
#include "../drivers/camera/fake_v4l2_device.hpp"
#include "pipeline/config/run_config.hpp"
#include "pipeline/realtime/pipeline_runner.hpp"
#include "pipeline/realtime/slam_stages.hpp"
#include "scripted_graph.hpp"

namespace svslam::rt {
namespace {

namespace fs = std::filesystem;
using drivers::testing::FakeCameraConfig;
using drivers::testing::FakeEvent;
using drivers::testing::FakeV4l2Device;

constexpr int kFrames = 40, kLastPaired = 14;
constexpr TimeNs kP = 50 * kNsPerMs;  // 20 Hz

// The fake driver shows (base + sequence) mod 256 at frame `sequence`: bases holding
// (image - sequence) mod 256 make it show the rendered image itself.
ImageU8 precompensated(const ImageU8& img, int sequence) {
  ImageU8 out(img.width(), img.height());
  for (int y = 0; y < img.height(); ++y)
    for (int x = 0; x < img.width(); ++x)
      out(x, y) = static_cast<std::uint8_t>((img(x, y) - sequence) & 0xFF);
  return out;
}

// Two equal pinhole cameras, no distortion, the right one baseline_m along +x: rectification
// is the identity up to the principal point stereoRectify chooses.
std::string writeCalib(const fs::path& dir, const StereoCalibration& c) {
  const fs::path path = dir / "stereo.yaml";
  cv::FileStorage f(path.string(), cv::FileStorage::WRITE);
  const cv::Mat K = (cv::Mat_<double>(3, 3) << c.f_px, 0, c.cx_px, 0, c.f_px, c.cy_px, 0, 0, 1);
  f << "K1" << K << "D1" << cv::Mat::zeros(1, 5, CV_64F);
  f << "K2" << K << "D2" << cv::Mat::zeros(1, 5, CV_64F);
  f << "R" << cv::Mat::eye(3, 3, CV_64F);
  f << "T" << (cv::Mat_<double>(3, 1) << -c.baseline_m, 0, 0);
  f << "image_width" << c.width << "image_height" << c.height;
  return path.string();
}

struct Flight {
  run::RunSummary summary;
  std::vector<Eigen::Isometry3d> poses;
  std::uint64_t right_losses = 0, left_only_frames = 0;
  std::string warnings;
  Eigen::Isometry3d gt_last = Eigen::Isometry3d::Identity();
};

// The flight through the fake V4L2 cameras with right_loss=left_only; the right camera leaves
// the bus after frame `last_paired` (never when >= kFrames - 1).
Flight fly(int last_paired) {
  Flight out;
  auto synth = drivers::openStereoSource("synthetic:width=320,height=240,frames=40");
  EXPECT_TRUE(synth.isOk()) << synth.status().message();
  if (!synth) return out;
  FakeCameraConfig left, right;
  drivers::StereoFrame f;
  for (int k = 0; k < kFrames; ++k) {
    auto more = (*synth)->next(f);
    EXPECT_TRUE(more.isOk() && *more) << "synthetic frame " << k;
    left.bases.push_back(precompensated(f.left, k));
    right.bases.push_back(precompensated(f.right, k));
    const TimeNs t = kNsPerS + k * kP;
    left.script.push_back(FakeEvent::frame(t, static_cast<std::uint32_t>(k)));
    if (k <= last_paired)
      right.script.push_back(FakeEvent::frame(t, static_cast<std::uint32_t>(k)));
  }
  if (last_paired < kFrames - 1)
    right.script.push_back(FakeEvent::enodev());  // gone for good (replug_after_opens -1)
  left.base = precompensated(left.bases[0], 0);  // a copy (for the format checks)
  right.base = precompensated(right.bases[0], 0);
  EXPECT_TRUE((*synth)->groundTruth(kFrames - 1, out.gt_last));
  FakeV4l2Device dev;
  dev.addCamera("/dev/video0", std::move(left));
  dev.addCamera("/dev/video1", std::move(right));

  const fs::path dir =
      fs::temp_directory_path() /
      ("svslam_right_unplug_" + std::to_string(::getpid()) + "_" + std::to_string(last_paired));
  fs::create_directories(dir);
  auto src = drivers::openV4l2Source("/dev/video0,/dev/video1?width=320&height=240&calib=" +
                                         writeCalib(dir, (*synth)->calibration()) +
                                         "&right_loss=left_only",
                                     dev);
  EXPECT_TRUE(src.isOk()) << src.status().message();
  if (!src) return out;
  config::RunConfig cfg;  // ekf, defaults
  cfg.threads = 1;
  {
    SlamStages work(cfg, **src, dir.string(), nullptr);
    EXPECT_TRUE(work.init().isOk());
    work.setMaxFrames(kFrames);
    PipelineOptions o;
    PipelineRunner runner(o, work.graph(EdgePolicy::kBlocking));
    auto slots = makeSlots(runner);
    PipelineControl control;
    const Status run = runner.run(slots, control, nullptr);
    EXPECT_TRUE(run.isOk()) << run.message();
    out.summary = work.summary();
    EXPECT_TRUE(work.finish().isOk());
  }
  auto* v4l2 = dynamic_cast<drivers::V4l2StereoSource*>(src->get());
  EXPECT_NE(v4l2, nullptr);
  if (v4l2) {
    out.right_losses = v4l2->rightLosses();
    out.left_only_frames = v4l2->leftOnlyFrames();
  }
  out.warnings = (*src)->takeWarnings();
  auto t = drivers::readTrajectory((dir / "trajectory_kitti.txt").string());
  EXPECT_TRUE(t.isOk()) << t.status().message();
  if (t) out.poses = t->poses;
  fs::remove_all(dir);
  return out;
}

double finalError(const Flight& f) {
  return (f.poses.back().translation() - f.gt_last.translation()).norm();
}

TEST(RightUnplug, EkfFliesOnTheLeftCameraFromTheFirstFrameWithoutTheRight) {
  const Flight both = fly(kFrames - 1), lost = fly(kLastPaired);
  ASSERT_EQ(both.poses.size(), static_cast<std::size_t>(kFrames));
  ASSERT_EQ(lost.poses.size(), static_cast<std::size_t>(kFrames));
  const run::RunSummary& s = lost.summary;
  EXPECT_EQ(s.frames, kFrames);
  // Every frame from the first without the right image is a mono frame, the right camera
  // "missing" (RightCameraState 1), one loss; the source says the same.
  const int alone = kFrames - (kLastPaired + 1);
  EXPECT_EQ(s.mono_frames, alone);
  EXPECT_EQ(s.right_camera_state_counts[1], alone);
  EXPECT_EQ(s.right_camera_losses, 1);
  EXPECT_GT(s.bearing_count, 0);
  EXPECT_EQ(lost.right_losses, 1u);
  EXPECT_EQ(lost.left_only_frames, static_cast<std::uint64_t>(alone));
  EXPECT_NE(lost.warnings.find("going on with the left camera alone"), std::string::npos)
      << lost.warnings;
  EXPECT_EQ(both.summary.mono_frames, 0);
  EXPECT_EQ(both.right_losses, 0u);
  for (std::size_t k = 0; k < lost.poses.size(); ++k)
    EXPECT_TRUE(lost.poses[k].matrix().allFinite()) << "frame " << k;
  // The same flight with both cameras through the same path is the reference (the rectified
  // camera is the synthetic one up to the principal point stereoRectify chooses).
  std::printf(
      "right camera unplugged after frame %d: %d mono frames, final position error %.3f m; "
      "both cameras %.3f m\n",
      kLastPaired, s.mono_frames, finalError(lost), finalError(both));
  EXPECT_LE(finalError(lost), 3.0 * finalError(both) + 0.01);
}

}  // namespace
}  // namespace svslam::rt
