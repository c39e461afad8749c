#pragma once
// Live stereo from V4L2 cameras (drivers::StereoSource, size() = -1).
//
//   v4l2:/dev/videoA,/dev/videoB[?options]   two free-running cameras; frames are paired by
//       timestamp: when the two oldest frames differ by more than sync_ms, the older one is
//       dropped (counted per camera) and the next frame of that camera is read.
//   v4l2:/dev/videoX?layout=side-by-side&... one device delivering both views side by side
//       (left view in the left half); width is the full frame width.
// Options (query string, '&'-separated key=value): width, height (px, default 640x480),
// fps (Hz, default 30), format (GREY|YUYV|MJPEG, default GREY), calib=FILE (required),
// sync_ms (pairing tolerance, ms, default 5), layout (stereo|side-by-side), buffers (default 4),
// timeout_ms (per frame, default 1000). An unknown key is an error naming it.
//
// Calibration file (OpenCV FileStorage YAML/XML/JSON): K1, D1, K2, D2 (intrinsics and
// distortion of the left/right raw cameras), R, T (p_right = R p_left + T, T in metres),
// image_width, image_height (one view, px; must equal the capture size of one view). The source
// rectifies with cv::stereoRectify (CALIB_ZERO_DISPARITY, alpha 0) + initUndistortRectifyMap +
// remap and reports the rectified StereoCalibration. Frame t_ns = the left camera's
// CLOCK_MONOTONIC timestamp.
#include <array>
#include <functional>
#include <map>
#include <memory>
#include <opencv2/core.hpp>
#include <set>
#include <string>
#include <vector>

#include "drivers/source/stereo_source.hpp"
#include "drivers/camera/v4l2_capture.hpp"
#include "drivers/camera/v4l2_device.hpp"

namespace svslam::drivers {

// "DEV1,DEV2?k=v&k=v" split into devices and options; keys outside `allowed` are an error that
// names the key and the `scheme` ("v4l2", "libcamera").
struct CameraSpec {
  std::vector<std::string> devices;
  std::map<std::string, std::string> options;
};
Result<CameraSpec> parseCameraSpec(const std::string& spec, const std::string& scheme,
                                   const std::set<std::string>& allowed);

// Rectification maps of a calibrated stereo pair and the rectified calibration.
struct StereoRectification {
  StereoCalibration calib;  // rectified: left camera, baseline along +x, same size as raw
  cv::Mat map_left_x, map_left_y, map_right_x, map_right_y;
  // Remaps raw views (calib.width x calib.height) into out.left / out.right.
  Status apply(const ImageU8& raw_left, const ImageU8& raw_right, StereoFrame& out) const;
};
// Reads `file` (format above); width/height = the capture size of one view, px.
Result<StereoRectification> loadStereoRectification(const std::string& file, int width, int height);

// Pairs the frames of two free-running cameras by timestamp (see top).
class TimestampPairer {
 public:
  // grab(camera 0|1, image, t_ns): a StereoSource-like read of one camera.
  using GrabFn = std::function<Result<bool>(int camera, ImageU8& image, TimeNs& t_ns)>;
  // tolerance_ns >= 0; more than max_drops_in_row drops without a pair is an error.
  TimestampPairer(TimeNs tolerance_ns, int max_drops_in_row = 30)
      : tolerance_ns_(tolerance_ns), max_drops_(max_drops_in_row) {}
  // True with a pair (t_ns = left timestamp); false when a camera ended.
  Result<bool> next(const GrabFn& grab, ImageU8& left, ImageU8& right, TimeNs& t_ns);
  std::uint64_t dropped(int camera) const { return dropped_[static_cast<std::size_t>(camera)]; }

 private:
  TimeNs tolerance_ns_;
  int max_drops_;
  std::array<ImageU8, 2> head_;
  std::array<TimeNs, 2> head_t_{};
  std::array<bool, 2> have_{};
  std::array<std::uint64_t, 2> dropped_{};
};

class V4l2StereoSource final : public StereoSource {
 public:
  // One capture = side-by-side, two = left and right cameras; all already open.
  V4l2StereoSource(std::vector<std::unique_ptr<V4l2Capture>> captures, StereoRectification rect,
                   TimeNs sync_tolerance_ns);
  const StereoCalibration& calibration() const override { return rect_.calib; }
  int size() const override { return -1; }
  Result<bool> next(StereoFrame& out) override;
  // Frames dropped by the pairing, per camera (0 left, 1 right).
  std::uint64_t unpairedDrops(int camera) const { return pairer_.dropped(camera); }
  const V4l2Capture& capture(int i) const { return *captures_[static_cast<std::size_t>(i)]; }

 private:
  std::vector<std::unique_ptr<V4l2Capture>> captures_;
  StereoRectification rect_;
  TimestampPairer pairer_;
  ImageU8 full_, raw_left_, raw_right_;
  int index_ = 0;
};

// The v4l2: spec checked and split (everything but the calibration file, which is only named).
struct V4l2Setup {
  V4l2CaptureParams params;          // device left empty; width = full frame width
  std::vector<std::string> devices;  // one (side-by-side) or two (left, right)
  bool side_by_side = false;
  TimeNs sync_tolerance_ns = 0;
  std::string calib;  // calib=FILE, "" when absent
  int viewWidth() const { return side_by_side ? params.width / 2 : params.width; }
};
Result<V4l2Setup> parseV4l2Setup(const std::string& spec_after_prefix);
// Opens and starts one capture per device of `setup` (raw frames, no rectification).
Result<std::vector<std::unique_ptr<V4l2Capture>>> openV4l2Captures(const V4l2Setup& setup,
                                                                   V4l2Device& device);

// `spec_after_prefix` = the spec without "v4l2:". Opens and starts the camera(s).
Result<std::unique_ptr<StereoSource>> openV4l2Source(const std::string& spec_after_prefix,
                                                     V4l2Device& device);
// Same through the process-wide SystemV4l2Device.
Result<std::unique_ptr<StereoSource>> openV4l2Source(const std::string& spec_after_prefix);

}  // namespace svslam::drivers
