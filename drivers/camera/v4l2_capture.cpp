// V4L2 mmap streaming capture (see v4l2_capture.hpp).
#include "drivers/camera/v4l2_capture.hpp"

#include <fcntl.h>
#include <linux/videodev2.h>
#include <sys/mman.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <ctime>

namespace svslam::drivers {
namespace {

std::string errnoText(int err) { return std::string(std::strerror(err)); }

std::string sizeText(std::uint32_t w, std::uint32_t h) {
  return std::to_string(w) + "x" + std::to_string(h);
}

TimeNs monotonicNowNs() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<TimeNs>(ts.tv_sec) * kNsPerS + static_cast<TimeNs>(ts.tv_nsec);
}

constexpr int kMaxEagainInRow = 100;

}  // namespace

Status V4l2CaptureParams::validate() const {
  if (device.empty()) return Status::invalidArgument("v4l2 capture: device path is empty");
  if (width < 1 || width > 16384 || height < 1 || height > 16384)
    return Status::invalidArgument("v4l2 capture " + device + ": size " + std::to_string(width) +
                                   "x" + std::to_string(height) + " outside [1, 16384]");
  if (!std::isfinite(fps) || fps < 0.0 || fps > 1000.0)
    return Status::invalidArgument("v4l2 capture " + device + ": fps must be in [0, 1000]");
  if (auto f = parsePixelFormat(format); !f)
    return Status::invalidArgument("v4l2 capture " + device + ": " + f.status().message());
  if (buffers < 2 || buffers > 32)
    return Status::invalidArgument("v4l2 capture " + device + ": buffers must be in [2, 32]");
  if (timeout_ms < 1 || timeout_ms > 60000)
    return Status::invalidArgument("v4l2 capture " + device + ": timeout_ms must be in [1, 60000]");
  if (max_bad_buffers < 0 || max_bad_buffers > 10000)
    return Status::invalidArgument("v4l2 capture " + device +
                                   ": max_bad_buffers must be in [0, 10000]");
  return Status::ok();
}

V4l2Capture::V4l2Capture(V4l2Device& device, V4l2CaptureParams params)
    : dev_(device), params_(std::move(params)) {}

V4l2Capture::~V4l2Capture() { (void)stop(); }

Status V4l2Capture::fail(const std::string& what, int err) {
  if (err == ENODEV) {
    unplugged_ = true;
    return Status::ioError("device unplugged: " + params_.device);
  }
  return Status::ioError(params_.device + ": " + what + " failed: " + errnoText(err));
}

Status V4l2Capture::open() {
  if (fd_ >= 0) return Status::failedPrecondition(params_.device + ": already open");
  if (Status s = params_.validate(); !s) return s;
  format_ = parsePixelFormat(params_.format).value();
  fd_ = dev_.open(params_.device, O_RDWR | O_NONBLOCK);
  if (fd_ < 0) {
    const int err = errno;
    if (err == ENOENT) return Status::notFound("no such video device: " + params_.device);
    if (err == EACCES)
      return Status::ioError("permission denied opening " + params_.device +
                             " (is the user in the 'video' group?)");
    return Status::ioError("cannot open " + params_.device + ": " + errnoText(err));
  }
  Status s = negotiateFormat();
  if (s) s = mapBuffers();
  if (s) {
    for (std::uint32_t i = 0; i < buffers_.size() && s; ++i) s = queueBuffer(i);
  }
  if (s) {
    int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (dev_.ioctl(fd_, VIDIOC_STREAMON, &type) < 0) s = fail("VIDIOC_STREAMON", errno);
  }
  if (!s) {
    (void)stop();
    return s;
  }
  streaming_ = true;
  unplugged_ = false;
  errors_in_row_ = 0;
  have_last_ = false;
  return Status::ok();
}

Status V4l2Capture::negotiateFormat() {
  v4l2_capability cap{};
  if (dev_.ioctl(fd_, VIDIOC_QUERYCAP, &cap) < 0) {
    const int err = errno;
    if (err == ENOTTY) return Status::invalidArgument(params_.device + " is not a V4L2 device");
    return fail("VIDIOC_QUERYCAP", err);
  }
  const std::uint32_t caps =
      (cap.capabilities & V4L2_CAP_DEVICE_CAPS) ? cap.device_caps : cap.capabilities;
  if (!(caps & V4L2_CAP_VIDEO_CAPTURE)) {
    if (caps & V4L2_CAP_VIDEO_CAPTURE_MPLANE)
      return Status::invalidArgument(params_.device +
                                     " is a multi-planar capture device (not supported)");
    return Status::invalidArgument(params_.device + " is not a video capture device");
  }
  if (!(caps & V4L2_CAP_STREAMING))
    return Status::invalidArgument(params_.device + " does not support streaming I/O");

  v4l2_format fmt{};
  fmt.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  fmt.fmt.pix.width = static_cast<std::uint32_t>(params_.width);
  fmt.fmt.pix.height = static_cast<std::uint32_t>(params_.height);
  fmt.fmt.pix.pixelformat = pixelFormatFourcc(format_);
  fmt.fmt.pix.field = V4L2_FIELD_NONE;
  if (dev_.ioctl(fd_, VIDIOC_S_FMT, &fmt) < 0) return fail("VIDIOC_S_FMT", errno);
  const v4l2_pix_format& pix = fmt.fmt.pix;
  if (pix.width != static_cast<std::uint32_t>(params_.width) ||
      pix.height != static_cast<std::uint32_t>(params_.height) ||
      pix.pixelformat != pixelFormatFourcc(format_))
    return Status::invalidArgument(
        params_.device + ": asked for " +
        sizeText(static_cast<std::uint32_t>(params_.width),
                 static_cast<std::uint32_t>(params_.height)) +
        " " + pixelFormatName(format_) + ", driver granted " + sizeText(pix.width, pix.height) +
        " " + fourccToString(pix.pixelformat) + " (list modes with v4l2-ctl --list-formats-ext)");
  bytes_per_line_ = pix.bytesperline;
  if (format_ != PixelFormat::kMjpeg && bytes_per_line_ < minBytesPerLine(format_, params_.width))
    bytes_per_line_ = minBytesPerLine(format_, params_.width);
  size_image_ = pix.sizeimage;

  if (params_.fps > 0.0) {  // best effort: many drivers ignore or round the rate
    v4l2_streamparm parm{};
    parm.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    parm.parm.capture.timeperframe.numerator = 1000;
    parm.parm.capture.timeperframe.denominator =
        static_cast<std::uint32_t>(std::lround(params_.fps * 1000.0));
    if (dev_.ioctl(fd_, VIDIOC_S_PARM, &parm) == 0) {
      const v4l2_fract& tpf = parm.parm.capture.timeperframe;
      if (tpf.numerator > 0) granted_fps_ = static_cast<double>(tpf.denominator) / tpf.numerator;
    }
  }
  return Status::ok();
}

Status V4l2Capture::mapBuffers() {
  v4l2_requestbuffers req{};
  req.count = static_cast<std::uint32_t>(params_.buffers);
  req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  req.memory = V4L2_MEMORY_MMAP;
  if (dev_.ioctl(fd_, VIDIOC_REQBUFS, &req) < 0) {
    const int err = errno;
    if (err == EINVAL)
      return Status::invalidArgument(params_.device + " does not support mmap streaming");
    return fail("VIDIOC_REQBUFS", err);
  }
  if (req.count < 2)
    return Status::ioError(params_.device + ": driver granted only " + std::to_string(req.count) +
                           " buffer(s), need >= 2");
  buffers_.reserve(req.count);
  for (std::uint32_t i = 0; i < req.count; ++i) {
    v4l2_buffer buf{};
    buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buf.memory = V4L2_MEMORY_MMAP;
    buf.index = i;
    if (dev_.ioctl(fd_, VIDIOC_QUERYBUF, &buf) < 0) return fail("VIDIOC_QUERYBUF", errno);
    void* p = dev_.mmap(nullptr, buf.length, PROT_READ | PROT_WRITE, MAP_SHARED, fd_,
                        static_cast<off_t>(buf.m.offset));
    if (p == MAP_FAILED) return fail("mmap of buffer " + std::to_string(i), errno);
    buffers_.push_back({p, buf.length});
  }
  return Status::ok();
}

Status V4l2Capture::queueBuffer(std::uint32_t index) {
  v4l2_buffer buf{};
  buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  buf.memory = V4L2_MEMORY_MMAP;
  buf.index = index;
  if (dev_.ioctl(fd_, VIDIOC_QBUF, &buf) < 0) return fail("VIDIOC_QBUF", errno);
  return Status::ok();
}

Status V4l2Capture::dropBuffer(const std::string& why) {
  ++stats_.dropped;
  if (++errors_in_row_ > params_.max_bad_buffers)
    return Status::ioError(params_.device + ": " + std::to_string(errors_in_row_) +
                           " bad buffers in a row (last: " + why + ")");
  return Status::ok();
}

Result<bool> V4l2Capture::grab(ImageU8& grey_out, TimeNs& t_ns_out, std::uint32_t& sequence_out) {
  if (!streaming_ || unplugged_) return false;
  int eagain_in_row = 0;
  auto failed = [](Status s) -> Result<bool> { return s; };
  const std::uint64_t dropped_before = stats_.dropped;
  auto timedOut = [&]() -> Result<bool> {
    const std::uint64_t bad = stats_.dropped - dropped_before;
    return Status::ioError("timeout: no frame from " + params_.device + " within " +
                           std::to_string(params_.timeout_ms) + " ms" +
                           (bad > 0 ? " (" + std::to_string(bad) + " bad buffers)" : ""));
  };
  // The whole call waits at most timeout_ms, also when bad buffers or EAGAIN keep coming.
  const TimeNs deadline = monotonicNowNs() + params_.timeout_ms * kNsPerMs;
  for (bool first = true;; first = false) {
    int wait_ms = params_.timeout_ms;
    if (!first) {
      const TimeNs left = deadline - monotonicNowNs();
      if (left <= 0) return timedOut();
      wait_ms = static_cast<int>((left + kNsPerMs - 1) / kNsPerMs);
    }
    pollfd pfd{fd_, POLLIN, 0};
    const int pr = dev_.poll(&pfd, 1, wait_ms);
    if (pr < 0) {
      if (errno == EINTR) {
        ++stats_.retries;
        continue;
      }
      return failed(fail("poll", errno));
    }
    if (pr == 0) return timedOut();
    v4l2_buffer buf{};
    buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buf.memory = V4L2_MEMORY_MMAP;
    buf.index = ~0u;
    if (dev_.ioctl(fd_, VIDIOC_DQBUF, &buf) < 0) {
      const int err = errno;
      if (err == EAGAIN || err == EINTR) {
        ++stats_.retries;
        if (++eagain_in_row > kMaxEagainInRow)
          return failed(Status::ioError(params_.device + ": VIDIOC_DQBUF keeps failing with " +
                                        errnoText(err)));
        continue;
      }
      if (err == EIO) {
        // The driver may or may not have dequeued a buffer; requeue it when it says which.
        if (buf.index < buffers_.size()) {
          if (Status s = queueBuffer(buf.index); !s) return failed(s);
        }
        if (Status s = dropBuffer("VIDIOC_DQBUF: EIO"); !s) return failed(s);
        continue;
      }
      return failed(fail("VIDIOC_DQBUF", err));
    }
    if (buf.index >= buffers_.size())
      return failed(Status::ioError(params_.device + ": driver returned buffer index " +
                                    std::to_string(buf.index) + " of " +
                                    std::to_string(buffers_.size())));
    std::string bad;
    TimeNs t_ns = 0;
    if (buf.flags & V4L2_BUF_FLAG_ERROR) {
      bad = "buffer flagged V4L2_BUF_FLAG_ERROR";
    } else {
      const std::size_t used = buf.bytesused > 0 ? buf.bytesused : buffers_[buf.index].length;
      const Status c =
          convertToGrey(format_, static_cast<const std::uint8_t*>(buffers_[buf.index].start),
                        std::min(used, buffers_[buf.index].length), params_.width, params_.height,
                        bytes_per_line_, grey_out);
      if (!c) bad = c.message();
    }
    if (bad.empty()) {
      if ((buf.flags & V4L2_BUF_FLAG_TIMESTAMP_MASK) == V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC) {
        t_ns = static_cast<TimeNs>(buf.timestamp.tv_sec) * kNsPerS +
               static_cast<TimeNs>(buf.timestamp.tv_usec) * kNsPerUs;
      } else {
        t_ns = monotonicNowNs();
        ++stats_.software_timestamps;
      }
    }
    if (Status s = queueBuffer(buf.index); !s) return failed(s);
    if (!bad.empty()) {
      if (Status s = dropBuffer(bad); !s) return failed(s);
      continue;
    }
    if (have_last_ && t_ns <= last_t_ns_) {
      ++stats_.non_monotonic;
      continue;
    }
    if (have_last_ && buf.sequence > last_sequence_ + 1)
      stats_.sequence_gaps += buf.sequence - last_sequence_ - 1;
    have_last_ = true;
    last_t_ns_ = t_ns;
    last_sequence_ = buf.sequence;
    errors_in_row_ = 0;
    ++stats_.frames;
    t_ns_out = t_ns;
    sequence_out = buf.sequence;
    return true;
  }
}

Status V4l2Capture::stop() {
  Status first;
  auto note = [&first](Status s) {
    if (first && !s) first = std::move(s);
  };
  if (fd_ < 0) return first;
  if (streaming_) {
    int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (dev_.ioctl(fd_, VIDIOC_STREAMOFF, &type) < 0 && errno != ENODEV)
      note(fail("VIDIOC_STREAMOFF", errno));
    streaming_ = false;
  }
  for (const Buffer& b : buffers_)
    if (dev_.munmap(b.start, b.length) < 0) note(fail("munmap", errno));
  if (!buffers_.empty()) {
    v4l2_requestbuffers req{};
    req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    req.memory = V4L2_MEMORY_MMAP;
    (void)dev_.ioctl(fd_, VIDIOC_REQBUFS, &req);  // release; old drivers refuse count 0
  }
  buffers_.clear();
  if (dev_.close(fd_) < 0) note(fail("close", errno));
  fd_ = -1;
  return first;
}

}  // namespace svslam::drivers
