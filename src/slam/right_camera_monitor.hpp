#pragma once
// RightCameraMonitor: decides, frame by frame, whether the right image of a stereo pair can be
// used (issue: flying on when one camera dies). The right image is unusable when it is
//  - missing: an empty view (the device stopped delivering, the caller passes no image) or one
//    whose size differs from the left image's;
//  - flat: its grey-level standard deviation, over a grid of at most 64 x 48 samples, is below
//    min_stddev (black, saturated or lens-capped);
//  - frozen: identical to the previous right image while the left image changed (a driver that
//    re-delivers one buffer). Two identical frames suffice: with a moving left camera a
//    repeated right image pairs wrong pixels at once.
// Hysteresis: once unusable, stereo resumes only after resume_frames consecutive usable right
// images (a flickering device does not toggle the estimator every frame).
// Pure: no clock, thread or I/O; the copies of the previous images are allocated on the first
// frame (and on a size change).
#include <cstdint>

#include "core/frozen_frame_detector.hpp"
#include "core/image.hpp"
#include "core/status.hpp"

namespace svslam {

struct RightCameraParams {
  bool enabled = true;       // false: the right image is always taken as usable
  double min_stddev = 2.0;   // grey levels; below: flat, >= 0
  int resume_frames = 3;     // consecutive usable frames before stereo resumes, [1, 1000]
  Status validate() const;
};

enum class RightCameraState : std::uint8_t { kOk = 0, kMissing = 1, kFlat = 2, kFrozen = 3 };
const char* rightCameraStateName(RightCameraState s);

class RightCameraMonitor {
 public:
  // Precondition: params.validate() is ok.
  explicit RightCameraMonitor(const RightCameraParams& params);
  // Classifies this frame's right image; returns whether stereo may be used for it.
  bool process(ImageView<const std::uint8_t> left, ImageView<const std::uint8_t> right);
  RightCameraState state() const { return state_; }  // this frame's classification
  bool usable() const { return usable_; }            // after hysteresis
  std::int64_t unusableFrames() const { return unusable_frames_; }
  std::int64_t losses() const { return losses_; }  // usable -> unusable transitions

 private:
  RightCameraParams params_;
  FrozenFrameDetector left_frozen_, right_frozen_;
  RightCameraState state_ = RightCameraState::kOk;
  bool usable_ = true;
  int good_run_ = 0;
  std::int64_t unusable_frames_ = 0;
  std::int64_t losses_ = 0;
};

}  // namespace svslam
