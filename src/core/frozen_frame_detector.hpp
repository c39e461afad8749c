#pragma once
// FrozenFrameDetector: notices a camera that keeps delivering the same image (a driver that
// re-delivers one buffer, a sensor that stopped while its bridge chip goes on streaming).
//
// run(k) = the number of consecutive frames up to and including frame k whose pixels are all
// equal to frame k's (run(0) = 1; run(k) = run(k-1) + 1 when frame k equals frame k-1, else 1).
// The camera is frozen at frame k when frozen_frames > 0 and run(k) >= frozen_frames; process()
// reports the frame at which run(k) == frozen_frames once per run (a new run after any change).
//
// The comparison is exact: frame k is compared with a copy of frame k-1 row by row (memcmp,
// which stops at the first differing byte, so a live frame with sensor noise costs a few bytes
// of comparison plus one copy; an identical frame costs a full comparison and no copy). A size
// change starts a new run. A uniformly black or saturated image repeated (lens cap, darkness)
// counts as frozen too: it carries nothing to track either.
//
// Pure: no clock, no thread, no I/O. The copy of the previous frame is allocated on the first
// frame (and on a size change), nothing afterwards.
#include <cstdint>

#include "core/image.hpp"
#include "core/status.hpp"

namespace svslam {

struct FrozenFrameParams {
  // Identical consecutive frames that make the camera frozen; 0 = detection off, else
  // [2, 1000000] (1 would call every frame frozen).
  int frozen_frames = 30;
  Status validate() const;
};

class FrozenFrameDetector {
 public:
  // Precondition: params.validate() is ok.
  explicit FrozenFrameDetector(FrozenFrameParams params) : params_(params) {}

  // Feeds the next frame; true exactly when this frame makes run() reach frozen_frames.
  // Does nothing (and returns false) when detection is off.
  bool process(ImageView<const std::uint8_t> frame);

  // run() of the last frame (0 before the first frame or when detection is off).
  int run() const { return run_; }
  bool frozen() const { return params_.frozen_frames > 0 && run_ >= params_.frozen_frames; }
  // Frames at which the camera became frozen (process() returned true) since construction.
  std::uint64_t detections() const { return detections_; }
  // The longest run seen, frames.
  int maxRun() const { return max_run_; }
  // Forgets the previous frame (the next frame starts a run of 1); counters stay.
  void reset() { run_ = 0; }
  const FrozenFrameParams& params() const { return params_; }

 private:
  FrozenFrameParams params_;
  ImageU8 previous_;
  int run_ = 0;
  int max_run_ = 0;
  std::uint64_t detections_ = 0;
};

}  // namespace svslam
