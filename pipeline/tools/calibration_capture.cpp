// Live calibration pair collection (see calibration_capture.hpp).
#include "pipeline/tools/calibration_capture.hpp"

#include "drivers/files/opencv_view.hpp"

namespace svslam::cli {

Status collectLivePairs(drivers::RawStereoCapture& capture, drivers::StereoCalibrator& calibrator,
                        const LiveCollectOptions& options, const std::function<Trigger()>& trigger,
                        const std::function<void(const std::string&)>& progress,
                        cv::Mat& check_left, cv::Mat& check_right, LiveCollectStats& stats) {
  if (options.grab_every < 0 || options.pairs < 1 || options.max_frames < 0)
    return Status::invalidArgument("live collection: grab_every >= 0, pairs >= 1, max_frames >= 0");
  ImageU8 left, right;
  TimeNs t_ns = 0;
  bool armed = false;
  while (calibrator.acceptedPairs() < options.pairs) {
    if (options.max_frames > 0 && stats.frames_read >= options.max_frames) break;
    if (options.grab_every == 0 && trigger) {
      const Trigger t = trigger();
      if (t == Trigger::kStop) break;
      armed = armed || t == Trigger::kGrab;
    }
    auto more = capture.next(left, right, t_ns);
    if (!more) return more.status();
    if (!*more) break;
    ++stats.frames_read;
    const bool grab = options.grab_every > 0 ? stats.frames_read % options.grab_every == 0 : armed;
    if (!grab) continue;
    armed = false;
    ++stats.offered;
    const std::string name = "frame" + std::to_string(stats.frames_read);
    bool accepted = false;
    if (Status s = calibrator.addPair(drivers::asMat(left), drivers::asMat(right), name, accepted);
        !s)
      return s;
    if (accepted && check_left.empty()) {
      drivers::asMat(left).copyTo(check_left);
      drivers::asMat(right).copyTo(check_right);
    }
    if (progress)
      progress(
          "pair " + std::to_string(stats.offered) + " (" + name +
          "): " + (accepted ? "accepted" : "rejected, " + calibrator.rejections().back().reason) +
          ", " + std::to_string(calibrator.acceptedPairs()) + "/" + std::to_string(options.pairs));
  }
  return Status::ok();
}

}  // namespace svslam::cli
