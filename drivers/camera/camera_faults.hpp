#pragma once
// Faults of live cameras handled by the v4l2: and libcamera: sources (docs/cameras.md):
// a frozen camera (the same image again and again) and the clock of the reconnect loop of a
// camera that was unplugged.
#include <cstdint>
#include <string>
#include <vector>

#include "core/frozen_frame_detector.hpp"
#include "core/image.hpp"
#include "core/status.hpp"
#include "core/time.hpp"
#include "drivers/source/stereo_source.hpp"

namespace svslam::drivers {

// Spec options frozen_frames and frozen_action.
struct FrozenCameraParams {
  FrozenFrameParams detector;  // frozen_frames: 0 = off, else [2, 1000000]; default 30
  bool end_run = true;  // frozen_action: error (true, the run ends) | warn (counted, goes on)
};

// One FrozenFrameDetector per camera of a live source, with the camera names for messages.
class FrozenCameraWatch {
 public:
  // `cameras`: the names used in messages (/dev/videoN, libcamera ids). Precondition:
  // params.detector.validate() is ok.
  FrozenCameraWatch(FrozenCameraParams params, std::vector<std::string> cameras);
  // Checks the next raw frame of camera `camera`. When this frame makes the camera frozen:
  // with end_run the error "camera frozen: NAME delivered the same image for N frames";
  // without, ok and `warning` set to that text (otherwise left alone).
  Status check(int camera, ImageView<const std::uint8_t> raw, std::string& warning);
  // Times camera `camera` became frozen.
  std::uint64_t detections(int camera) const;
  // The longest run of identical frames of camera `camera`, frames.
  int maxRun(int camera) const;
  // Forgets the previous frames (after a reconnect: a new stream starts).
  void reset();
  const std::string& name(int camera) const { return cameras_[static_cast<std::size_t>(camera)]; }

 private:
  FrozenCameraParams params_;
  std::vector<std::string> cameras_;
  std::vector<FrozenFrameDetector> detectors_;
};

// The monotonic clock and the wait of the reconnect loop (tests pass a virtual one).
class ReconnectClock {
 public:
  virtual ~ReconnectClock() = default;
  virtual TimeNs nowNs() = 0;
  // Waits `ns` (> 0) or until `stop` (when set) returns true, polled at least every
  // kStopPollNs; true when stopped.
  virtual bool waitNs(TimeNs ns, const StopQuery& stop) = 0;
  static constexpr TimeNs kStopPollNs = 50 * kNsPerMs;
};
// CLOCK_MONOTONIC and nanosleep (process-wide, stateless).
ReconnectClock& systemReconnectClock();

}  // namespace svslam::drivers
