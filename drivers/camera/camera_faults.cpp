// Frozen-camera watch and the reconnect clock (see camera_faults.hpp).
#include "drivers/camera/camera_faults.hpp"

#include <algorithm>
#include <cerrno>
#include <ctime>

namespace svslam::drivers {

FrozenCameraWatch::FrozenCameraWatch(FrozenCameraParams params, std::vector<std::string> cameras)
    : params_(params), cameras_(std::move(cameras)) {
  detectors_.reserve(cameras_.size());
  for (std::size_t i = 0; i < cameras_.size(); ++i) detectors_.emplace_back(params_.detector);
}

Status FrozenCameraWatch::check(int camera, ImageView<const std::uint8_t> raw,
                                std::string& warning) {
  FrozenFrameDetector& d = detectors_[static_cast<std::size_t>(camera)];
  if (!d.process(raw)) return Status::ok();
  const std::string what = "camera frozen: " + name(camera) + " delivered the same image for " +
                           std::to_string(d.run()) + " frames";
  if (params_.end_run) return Status::ioError(what);
  warning = what;
  return Status::ok();
}

std::uint64_t FrozenCameraWatch::detections(int camera) const {
  return detectors_[static_cast<std::size_t>(camera)].detections();
}

int FrozenCameraWatch::maxRun(int camera) const {
  return detectors_[static_cast<std::size_t>(camera)].maxRun();
}

void FrozenCameraWatch::reset() {
  for (FrozenFrameDetector& d : detectors_) d.reset();
}

namespace {

class SystemReconnectClock final : public ReconnectClock {
 public:
  TimeNs nowNs() override {
    timespec ts{};
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return static_cast<TimeNs>(ts.tv_sec) * kNsPerS + static_cast<TimeNs>(ts.tv_nsec);
  }
  bool waitNs(TimeNs ns, const StopQuery& stop) override {
    const TimeNs end = nowNs() + ns;
    for (;;) {
      if (stop && stop()) return true;
      const TimeNs left = end - nowNs();
      if (left <= 0) return false;
      const TimeNs slice = std::min(left, kStopPollNs);
      timespec ts{static_cast<time_t>(slice / kNsPerS), static_cast<long>(slice % kNsPerS)};
      while (nanosleep(&ts, &ts) != 0 && errno == EINTR) {
        if (stop && stop()) return true;
      }
    }
  }
};

}  // namespace

ReconnectClock& systemReconnectClock() {
  static SystemReconnectClock clock;
  return clock;
}

}  // namespace svslam::drivers
