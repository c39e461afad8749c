#pragma once
// Live stereo from two libcamera cameras (drivers::StereoSource, size() = -1). Compiled only when
// libcamera is found (SVSLAM_HAVE_LIBCAMERA); otherwise openStereoSource("libcamera:...")
// answers "libcamera support not built".
//
//   libcamera:ID_LEFT,ID_RIGHT[?width=W&height=H&calib=FILE&sync_ms=T&timeout_ms=T
//                              &frozen_frames=N&frozen_action=error|warn]
// IDs are libcamera camera ids (`cam --list` or the error message below lists them). Each camera
// is configured with StreamRole::VideoRecording at W x H (default 640x480) in a format whose
// first plane is 8-bit luma (R8, YUV420, NV12; YUYV and MJPEG also accepted) and must grant
// exactly that size. Frames are paired by SensorTimestamp (ns, the kernel's CLOCK_MONOTONIC
// buffer time) within sync_ms (default 5 ms), as in v4l2_source.hpp, and rectified from
// calib=FILE (required; format in v4l2_source.hpp / docs/cameras.md). Each camera's raw frames
// go through the frozen-camera check of the v4l2: source (frozen_frames, default 30; 0 = off).
// No reconnect: a camera error ends the stream.
//
// Errors: an unknown ID (or no camera at all) -> "libcamera: camera 'X' not found (N cameras:
// ids...)"; a camera in use by another process -> an error naming it. libcamera allows one
// CameraManager per process, so only one libcamera source can be open at a time.
#include <memory>
#include <string>

#include "drivers/camera/raw_stereo_capture.hpp"
#include "drivers/source/stereo_source.hpp"

namespace svslam::drivers {

// `spec_after_prefix` = the spec without "libcamera:".
Result<std::unique_ptr<StereoSource>> openLibcameraSource(const std::string& spec_after_prefix);
// The same cameras unrectified (calib= not needed, ignored), for calibrating them.
Result<std::unique_ptr<RawStereoCapture>> openLibcameraRawCapture(
    const std::string& spec_after_prefix);

}  // namespace svslam::drivers
