#include "slam/right_camera_monitor.hpp"

#include <algorithm>
#include <cmath>

namespace svslam {

Status RightCameraParams::validate() const {
  if (!(min_stddev >= 0) || !std::isfinite(min_stddev))
    return Status::invalidArgument("right_camera.min_stddev must be finite and >= 0");
  if (resume_frames < 1 || resume_frames > 1000)
    return Status::invalidArgument("right_camera.resume_frames must be in [1, 1000]");
  return Status::ok();
}

const char* rightCameraStateName(RightCameraState s) {
  switch (s) {
    case RightCameraState::kOk: return "ok";
    case RightCameraState::kMissing: return "missing";
    case RightCameraState::kFlat: return "flat";
    case RightCameraState::kFrozen: return "frozen";
  }
  return "unknown";
}

RightCameraMonitor::RightCameraMonitor(const RightCameraParams& params)
    : params_(params), left_frozen_({2}), right_frozen_({2}) {}

namespace {

// Grey-level standard deviation over a grid of at most 64 x 48 samples.
double sampledStddev(ImageView<const std::uint8_t> im) {
  const int nx = std::min(64, im.width), ny = std::min(48, im.height);
  double s = 0, s2 = 0;
  for (int j = 0; j < ny; ++j) {
    const int y = static_cast<int>((2 * j + 1) * static_cast<long>(im.height) / (2 * ny));
    for (int i = 0; i < nx; ++i) {
      const int x = static_cast<int>((2 * i + 1) * static_cast<long>(im.width) / (2 * nx));
      const double v = im(x, y);
      s += v;
      s2 += v * v;
    }
  }
  const double n = static_cast<double>(nx) * ny, mean = s / n;
  return std::sqrt(std::max(0.0, s2 / n - mean * mean));
}

}  // namespace

bool RightCameraMonitor::process(ImageView<const std::uint8_t> left,
                                 ImageView<const std::uint8_t> right) {
  if (!params_.enabled) {
    state_ = RightCameraState::kOk;
    return usable_ = true;
  }
  if (!left.empty()) left_frozen_.process(left);
  if (right.empty() || right.width != left.width || right.height != left.height) {
    state_ = RightCameraState::kMissing;
    right_frozen_.reset();
  } else {
    right_frozen_.process(right);
    if (sampledStddev(right) < params_.min_stddev)
      state_ = RightCameraState::kFlat;
    else if (right_frozen_.run() >= 2 && left_frozen_.run() < 2)
      state_ = RightCameraState::kFrozen;  // both repeated: a still scene, not a frozen camera
    else
      state_ = RightCameraState::kOk;
  }
  const bool good = state_ == RightCameraState::kOk;
  if (!good) {
    ++unusable_frames_;
    if (usable_) ++losses_;
    usable_ = false;
    good_run_ = 0;
  } else if (!usable_) {
    if (++good_run_ >= params_.resume_frames) usable_ = true;
  }
  return usable_;
}

}  // namespace svslam
