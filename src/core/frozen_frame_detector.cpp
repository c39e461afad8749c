// Identical consecutive frames (see frozen_frame_detector.hpp).
#include "core/frozen_frame_detector.hpp"

#include <cstring>
#include <limits>
#include <string>

namespace svslam {

Status FrozenFrameParams::validate() const {
  if (frozen_frames != 0 && (frozen_frames < 2 || frozen_frames > 1000000))
    return Status::invalidArgument("frozen_frames must be 0 (off) or in [2, 1000000], got " +
                                   std::to_string(frozen_frames));
  return Status::ok();
}

bool FrozenFrameDetector::process(ImageView<const std::uint8_t> frame) {
  if (params_.frozen_frames <= 0 || frame.empty()) return false;
  const auto row_bytes = static_cast<std::size_t>(frame.width);
  bool same = run_ > 0 && previous_.width() == frame.width && previous_.height() == frame.height;
  for (int y = 0; same && y < frame.height; ++y)
    same = std::memcmp(previous_.row(y), frame.row(y), row_bytes) == 0;
  if (same) {
    if (run_ < std::numeric_limits<int>::max()) ++run_;
  } else {
    previous_.resize(frame.width, frame.height);
    for (int y = 0; y < frame.height; ++y) std::memcpy(previous_.row(y), frame.row(y), row_bytes);
    run_ = 1;
  }
  if (run_ > max_run_) max_run_ = run_;
  if (run_ != params_.frozen_frames) return false;  // reached once per run: run_ grows by 1
  ++detections_;
  return true;
}

}  // namespace svslam
