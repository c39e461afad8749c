#pragma once
// V4l2Capture: one V4L2 video-capture device streaming through mmap'ed buffers, converted to
// 8-bit grey (pixel_formats.hpp). Single-planar capture only (V4L2_CAP_VIDEO_CAPTURE +
// V4L2_CAP_STREAMING); multi-planar devices are refused with a message saying so.
//
// Life cycle: open() = open O_NONBLOCK, QUERYCAP, S_FMT (what the driver granted must equal what
// was asked, else an error stating both), S_PARM for the frame rate (best effort), REQBUFS +
// QUERYBUF + mmap, QBUF all, STREAMON. grab() = poll, DQBUF, convert, QBUF. stop() = STREAMOFF,
// munmap, REQBUFS 0, close; the destructor calls stop().
//
// Timestamps: t_ns is the driver's CLOCK_MONOTONIC buffer timestamp (timeval -> ns) when the
// buffer carries V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC; otherwise CLOCK_MONOTONIC read at dequeue
// (counted in stats().software_timestamps). A frame whose timestamp is not later than the
// previous one is dropped and counted (non_monotonic), so returned t_ns strictly increase.
//
// Recovery in grab(): EAGAIN / EINTR -> poll again (counted in retries); EIO or a buffer with
// V4L2_BUF_FLAG_ERROR (or a frame that does not convert, e.g. corrupt MJPEG) -> the buffer is
// requeued and counted in dropped; more than max_bad_buffers such buffers in a row -> error
// "/dev/videoN: K bad buffers in a row (last: ...)"; ENODEV -> "device unplugged: /dev/videoN"
// (unplugged() then true; stop() and open() again once the device is back); no frame within
// timeout_ms of the call, whatever came instead -> "timeout: no frame from /dev/videoN within
// T ms". The device interface is injected (tests drive a fake).
#include <cstdint>
#include <string>
#include <vector>

#include "core/image.hpp"
#include "core/status.hpp"
#include "core/time.hpp"
#include "drivers/camera/pixel_formats.hpp"
#include "drivers/camera/v4l2_device.hpp"

namespace svslam::drivers {

struct V4l2CaptureParams {
  std::string device;           // device node, e.g. "/dev/video0"
  int width = 640;              // requested frame width, px, [1, 16384]
  int height = 480;             // requested frame height, px, [1, 16384]
  double fps = 30.0;            // requested frame rate, Hz, [0, 1000]; 0 = leave the driver's
  std::string format = "GREY";  // "GREY", "YUYV" or "MJPEG"
  int buffers = 4;              // mmap buffers requested, [2, 32]
  int timeout_ms = 1000;        // longest wait for one frame, ms, [1, 60000]
  int max_bad_buffers = 30;     // errored buffers tolerated in a row, [0, 10000]
  Status validate() const;
};

struct V4l2CaptureStats {
  std::uint64_t frames = 0;               // frames returned by grab()
  std::uint64_t dropped = 0;              // buffers dropped: EIO, FLAG_ERROR, not convertible
  std::uint64_t retries = 0;              // EAGAIN / EINTR retries of poll + DQBUF
  std::uint64_t non_monotonic = 0;        // frames dropped for a timestamp not increasing
  std::uint64_t sequence_gaps = 0;        // frames the driver skipped (sequence jumps)
  std::uint64_t software_timestamps = 0;  // frames without a monotonic driver timestamp
};

class V4l2Capture {
 public:
  // `device` must outlive this object. Does not touch the device until open().
  V4l2Capture(V4l2Device& device, V4l2CaptureParams params);
  ~V4l2Capture();
  V4l2Capture(const V4l2Capture&) = delete;
  V4l2Capture& operator=(const V4l2Capture&) = delete;

  // Validates the parameters, negotiates the format and starts streaming.
  Status open();
  // Waits for the next frame: true with grey_out (width x height), t_ns_out (CLOCK_MONOTONIC,
  // ns) and the driver's sequence number; false when not streaming (never opened, stopped, or
  // the device was unplugged); an error as described above (after a timeout or too many bad
  // buffers the caller may call grab() again).
  Result<bool> grab(ImageU8& grey_out, TimeNs& t_ns_out, std::uint32_t& sequence_out);
  // Stops streaming and releases buffers and the file descriptor; idempotent.
  Status stop();

  bool streaming() const { return streaming_; }
  // True after grab() met ENODEV, until the next successful open().
  bool unplugged() const { return unplugged_; }
  const V4l2CaptureParams& params() const { return params_; }
  const V4l2CaptureStats& stats() const { return stats_; }
  // The frame rate the driver reports after S_PARM, Hz (0 when unknown).
  double grantedFps() const { return granted_fps_; }

 private:
  struct Buffer {
    void* start = nullptr;
    std::size_t length = 0;
  };
  Status fail(const std::string& what, int err);
  Status negotiateFormat();
  Status mapBuffers();
  Status queueBuffer(std::uint32_t index);
  // Counts an errored buffer; the error once more than max_bad_buffers happened in a row.
  Status dropBuffer(const std::string& why);

  V4l2Device& dev_;
  V4l2CaptureParams params_;
  PixelFormat format_ = PixelFormat::kGrey;
  int fd_ = -1;
  bool streaming_ = false;
  bool unplugged_ = false;
  std::vector<Buffer> buffers_;
  std::size_t bytes_per_line_ = 0;
  std::size_t size_image_ = 0;
  double granted_fps_ = 0.0;
  int errors_in_row_ = 0;
  bool have_last_ = false;
  TimeNs last_t_ns_ = 0;
  std::uint32_t last_sequence_ = 0;
  V4l2CaptureStats stats_;
};

}  // namespace svslam::drivers
