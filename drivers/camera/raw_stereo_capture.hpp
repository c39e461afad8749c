#pragma once
// Unrectified stereo pairs from the live cameras, for calibrating them (svslam calibrate).
//
//   v4l2:...       the v4l2: spec of v4l2_source.hpp; calib= is not needed and ignored
//   libcamera:...  the libcamera: spec of libcamera_source.hpp; likewise
// Two cameras are paired by timestamp within sync_ms (TimestampPairer), a side-by-side device
// is split; the views come out as captured (grey, width x height of one view), no remap.
#include <memory>
#include <string>

#include "core/image.hpp"
#include "core/status.hpp"
#include "core/time.hpp"
#include "drivers/camera/v4l2_device.hpp"

namespace svslam::drivers {

class RawStereoCapture {
 public:
  virtual ~RawStereoCapture() = default;
  // The next raw pair (t_ns = left timestamp, CLOCK_MONOTONIC); false when a camera stopped.
  virtual Result<bool> next(ImageU8& left, ImageU8& right, TimeNs& t_ns) = 0;
};

// `spec` with its "v4l2:" or "libcamera:" prefix; the v4l2 cameras go through `device`.
Result<std::unique_ptr<RawStereoCapture>> openRawStereoCapture(const std::string& spec,
                                                               V4l2Device& device);
// Same through the process-wide SystemV4l2Device.
Result<std::unique_ptr<RawStereoCapture>> openRawStereoCapture(const std::string& spec);

}  // namespace svslam::drivers
