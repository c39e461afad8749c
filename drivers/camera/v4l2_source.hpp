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
// timeout_ms (per frame, default 1000), max_bad_buffers (errored buffers in a row, default 30),
// reconnect_timeout_s (default 5; 0 = none), reconnect_interval_ms (default 200),
// frozen_frames (default 30; 0 = off), frozen_action (error|warn, default error). An unknown key
// or a value out of range is an error naming it.
//
// Unplug (a capture meets ENODEV): with reconnect_timeout_s > 0 the source stops every capture
// and opens them all again (open, format, buffers, STREAMON) right away and then every
// reconnect_interval_ms until they all open or reconnect_timeout_s has passed, then goes on
// with the next pair; frames lost = round(gap * fps) - 1 with gap the time between the pairs
// before and after (counted, with the reconnects, in counters()). Not back in time: the error
// "device unplugged: /dev/videoN (not back within T s, K attempts; last: ...)"; with
// reconnect_timeout_s = 0 at once "device unplugged: /dev/videoN". The wait polls the stop
// query: a stop request ends the stream (next() false).
//
// Frozen camera: each device's raw frames go through a FrozenFrameDetector (camera_faults.hpp);
// frozen_frames identical frames in a row -> "camera frozen: /dev/videoN delivered the same
// image for N frames", the run's error (frozen_action=error) or a warning (warn).
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
#include <mutex>
#include <opencv2/core.hpp>
#include <set>
#include <string>
#include <vector>

#include "drivers/camera/camera_faults.hpp"
#include "drivers/camera/v4l2_capture.hpp"
#include "drivers/camera/v4l2_device.hpp"
#include "drivers/source/stereo_source.hpp"

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
  // The left view alone (the right camera lost): out.right is left empty (0 x 0).
  Status applyLeft(const ImageU8& raw_left, StereoFrame& out) const;
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
  // Forgets the frames waiting for a partner (the cameras restarted); counts stay.
  void reset() { have_ = {false, false}; }
  // Moves out the frame of `camera` waiting for a partner (false when none), which is then no
  // longer waiting.
  bool takeHead(int camera, ImageU8& image, TimeNs& t_ns) {
    const auto i = static_cast<std::size_t>(camera);
    if (!have_[i]) return false;
    std::swap(image, head_[i]);
    t_ns = head_t_[i];
    have_[i] = false;
    return true;
  }
  std::uint64_t dropped(int camera) const { return dropped_[static_cast<std::size_t>(camera)]; }

 private:
  TimeNs tolerance_ns_;
  int max_drops_;
  std::array<ImageU8, 2> head_;
  std::array<TimeNs, 2> head_t_{};
  std::array<bool, 2> have_{};
  std::array<std::uint64_t, 2> dropped_{};
};

// Spec options reconnect_timeout_s and reconnect_interval_ms.
struct ReconnectParams {
  double timeout_s = 5.0;  // how long to try to reopen unplugged cameras, s, [0, 3600]; 0 = never
  int interval_ms = 200;   // between two attempts, ms, [10, 60000]
};

// What a V4l2StereoSource needs besides its captures and rectification.
struct V4l2SourceOptions {
  TimeNs sync_tolerance_ns = 5 * kNsPerMs;
  ReconnectParams reconnect;
  // Spec option right_loss=left_only (two cameras): when the right camera is unplugged the
  // source goes on with the left one, delivering frames whose right view is empty, and tries to
  // reopen the right one every reconnect.interval_ms between frames (never waiting for it);
  // when it is back, pairs resume. Default (right_loss=reconnect): both cameras stop and are
  // reopened together, as for a left unplug.
  bool right_loss_left_only = false;
  FrozenCameraParams frozen;
  StopQuery stop;                   // polled while waiting to reconnect; empty = never stop
  ReconnectClock* clock = nullptr;  // nullptr = systemReconnectClock(); must outlive the source
};

class V4l2StereoSource final : public StereoSource {
 public:
  // One capture = side-by-side, two = left and right cameras; all already open.
  V4l2StereoSource(std::vector<std::unique_ptr<V4l2Capture>> captures, StereoRectification rect,
                   V4l2SourceOptions options);
  const StereoCalibration& calibration() const override { return rect_.calib; }
  int size() const override { return -1; }
  Result<bool> next(StereoFrame& out) override;
  std::string takeWarnings() override;
  // reconnects, reconnect_frames_lost, reconnect_wait_ms, right_losses, left_only_frames
  // (right_loss=left_only), then per camera (left_, right_; one device side by side: sbs_)
  // frames, dropped, retries, non_monotonic, sequence_gaps, software_timestamps, unpaired (two
  // cameras), frozen, max_identical_run.
  std::vector<std::pair<std::string, std::int64_t>> counters() const override;
  // Frames dropped by the pairing, per camera (0 left, 1 right).
  std::uint64_t unpairedDrops(int camera) const { return pairer_.dropped(camera); }
  const V4l2Capture& capture(int i) const { return *captures_[static_cast<std::size_t>(i)]; }
  std::uint64_t reconnects() const { return reconnects_; }
  std::uint64_t framesLostReconnecting() const { return frames_lost_; }
  std::uint64_t frozenDetections(int camera) const { return frozen_.detections(camera); }
  std::uint64_t rightLosses() const { return right_losses_; }
  std::uint64_t leftOnlyFrames() const { return left_only_frames_; }

 private:
  Result<bool> grabRaw(TimeNs& t_ns);
  // After an unplug: true once every capture streams again, false when stopped, else the error.
  Result<bool> reconnect(const Status& unplugged);
  void warn(const std::string& line);
  // right_loss=left_only: the right camera is gone (`unplugged` its error).
  void loseRight(const Status& unplugged);
  // A frame from the left camera alone, after a reopen attempt of the right one when due
  // (when it succeeds: a pair again).
  Result<bool> nextLeftOnly(StereoFrame& out);
  // Frozen check, frames-lost estimate after a reconnect, rectification and numbering of the
  // frame grabbed at t_ns (right view empty when left_only).
  Result<bool> deliver(TimeNs t_ns, bool left_only, StereoFrame& out);

  std::vector<std::unique_ptr<V4l2Capture>> captures_;
  StereoRectification rect_;
  V4l2SourceOptions options_;
  ReconnectClock* clock_;
  TimestampPairer pairer_;
  FrozenCameraWatch frozen_;
  ImageU8 full_, raw_left_, raw_right_;
  int index_ = 0;
  bool have_last_t_ = false;
  TimeNs last_t_ns_ = 0;
  bool reconnected_ = false;  // the next pair is the first after a reconnect
  TimeNs outage_start_ns_ = 0;
  std::uint64_t reconnects_ = 0, frames_lost_ = 0;
  TimeNs reconnect_wait_ns_ = 0;
  bool right_lost_ = false;
  TimeNs right_lost_since_ns_ = 0, next_right_attempt_ns_ = 0;
  std::uint64_t right_losses_ = 0, left_only_frames_ = 0;
  std::mutex warn_mutex_;
  std::string warnings_;
};

// The v4l2: spec checked and split (everything but the calibration file, which is only named).
struct V4l2Setup {
  V4l2CaptureParams params;          // device left empty; width = full frame width
  std::vector<std::string> devices;  // one (side-by-side) or two (left, right)
  bool side_by_side = false;
  TimeNs sync_tolerance_ns = 0;
  ReconnectParams reconnect;
  bool right_loss_left_only = false;  // right_loss=left_only
  FrozenCameraParams frozen;
  std::string calib;  // calib=FILE, "" when absent
  int viewWidth() const { return side_by_side ? params.width / 2 : params.width; }
};
Result<V4l2Setup> parseV4l2Setup(const std::string& spec_after_prefix);
// Opens and starts one capture per device of `setup` (raw frames, no rectification).
Result<std::vector<std::unique_ptr<V4l2Capture>>> openV4l2Captures(const V4l2Setup& setup,
                                                                   V4l2Device& device);

// frozen_frames and frozen_action of a camera spec (scheme "v4l2" or "libcamera" in messages).
Result<FrozenCameraParams> parseFrozenOptions(const CameraSpec& spec, const std::string& scheme);

// `spec_after_prefix` = the spec without "v4l2:". Opens and starts the camera(s). `stop` is
// polled while the source waits for an unplugged camera; `clock` (nullptr = the system's) must
// outlive the source.
Result<std::unique_ptr<StereoSource>> openV4l2Source(const std::string& spec_after_prefix,
                                                     V4l2Device& device, const StopQuery& stop = {},
                                                     ReconnectClock* clock = nullptr);
// Same through the process-wide SystemV4l2Device.
Result<std::unique_ptr<StereoSource>> openV4l2Source(const std::string& spec_after_prefix,
                                                     const StopQuery& stop = {});

}  // namespace svslam::drivers
