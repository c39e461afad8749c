// Scripted fake V4L2 driver (see fake_v4l2_device.hpp).
#include "fake_v4l2_device.hpp"

#include <linux/videodev2.h>
#include <sys/mman.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <opencv2/imgcodecs.hpp>
#include <thread>

namespace svslam::drivers::testing {
namespace {
constexpr off_t kOffsetStep = 1 << 24;  // mmap offset of buffer i: i * kOffsetStep

int fail(int err) {
  errno = err;
  return -1;
}
}  // namespace

ImageU8 expectedFrame(const ImageU8& base, std::uint32_t sequence) {
  ImageU8 out(base.width(), base.height());
  for (int y = 0; y < base.height(); ++y)
    for (int x = 0; x < base.width(); ++x)
      out(x, y) = static_cast<std::uint8_t>((base(x, y) + sequence) & 0xFF);
  return out;
}

ImageU8 testPattern(int width, int height, int seed) {
  ImageU8 img(width, height);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const double v = 110.0 + 50.0 * std::sin(0.11 * x + 0.3 * seed) * std::cos(0.07 * y) +
                       30.0 * std::sin(0.023 * (x + 2 * y)) + ((x / 16 + y / 16) % 2 ? 20 : 0);
      img(x, y) = static_cast<std::uint8_t>(std::clamp(v, 0.0, 255.0));
    }
  return img;
}

void FakeV4l2Device::addCamera(const std::string& path, FakeCameraConfig config) {
  Camera cam;
  cam.config = std::move(config);
  cams_[path] = std::move(cam);
}

FakeV4l2Device::Camera* FakeV4l2Device::cameraOf(int fd) {
  auto it = fds_.find(fd);
  return it == fds_.end() ? nullptr : &cams_.at(it->second);
}

void FakeV4l2Device::unplug(const std::string& path) {
  Camera& cam = cams_.at(path);
  cam.unplugged = true;
  cam.streaming = false;
  cam.failed_opens = 0;
}

void FakeV4l2Device::plug(const std::string& path) {
  Camera& cam = cams_.at(path);
  cam.unplugged = false;
  cam.streaming = false;
  cam.queue.clear();
}

int FakeV4l2Device::open(const std::string& path, int flags) {
  (void)flags;
  auto it = cams_.find(path);
  if (it == cams_.end()) return fail(ENOENT);
  Camera& cam = it->second;
  ++cam.opens;
  if (cam.unplugged) {
    const int back_after = cam.config.replug_after_opens;
    if (back_after < 0 || cam.failed_opens < back_after) {
      ++cam.failed_opens;
      return fail(cam.config.absent_errno);
    }
    plug(path);
  }
  const int fd = next_fd_++;
  fds_[fd] = path;
  return fd;
}

int FakeV4l2Device::close(int fd) {
  Camera* cam = cameraOf(fd);
  if (cam == nullptr) return fail(EBADF);
  cam->streaming = false;
  cam->queue.clear();
  fds_.erase(fd);
  return 0;
}

void FakeV4l2Device::fill(Camera& cam, std::uint32_t index, std::uint32_t sequence,
                          std::uint32_t& bytes_used) {
  const ImageU8& base = cam.config.bases.empty()
                            ? cam.config.base
                            : cam.config.bases[sequence % cam.config.bases.size()];
  const std::int64_t freeze = cam.config.freeze_from_sequence;
  const ImageU8 frame = expectedFrame(
      base, freeze >= 0 && sequence >= freeze ? static_cast<std::uint32_t>(freeze) : sequence);
  std::vector<std::uint8_t>& buf = cam.buffers[index];
  const int w = static_cast<int>(cam.width), h = static_cast<int>(cam.height);
  std::fill(buf.begin(), buf.end(), std::uint8_t{0xEE});  // padding shows up if misread
  if (cam.fourcc == V4L2_PIX_FMT_MJPEG) {
    std::vector<std::uint8_t> jpg;
    cv::Mat m(h, w, CV_8U);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        m.at<std::uint8_t>(y, x) = frame(x % frame.width(), y % frame.height());
    cv::imencode(".jpg", m, jpg, {cv::IMWRITE_JPEG_QUALITY, 98});
    std::copy(jpg.begin(),
              std::min(jpg.end(), jpg.begin() + static_cast<std::ptrdiff_t>(buf.size())),
              buf.begin());
    bytes_used = static_cast<std::uint32_t>(std::min(jpg.size(), buf.size()));
    return;
  }
  const bool yuyv = cam.fourcc == V4L2_PIX_FMT_YUYV;
  for (int y = 0; y < h; ++y) {
    std::uint8_t* row = buf.data() + static_cast<std::size_t>(y) * cam.bytes_per_line;
    for (int x = 0; x < w; ++x) {
      const std::uint8_t v = frame(x % frame.width(), y % frame.height());
      if (yuyv) {
        row[2 * x] = v;
        row[2 * x + 1] = static_cast<std::uint8_t>(x % 2 ? 100 : 150);  // chroma
      } else {
        row[x] = v;
      }
    }
  }
  bytes_used = cam.size_image;
}

int FakeV4l2Device::dqbuf(Camera& cam, void* arg) {
  auto* b = static_cast<v4l2_buffer*>(arg);
  if (cam.unplugged) return fail(ENODEV);
  if (!cam.streaming) return fail(EINVAL);
  if (cam.config.script.empty() || cam.config.script.front().kind == FakeEvent::Kind::kTimeout)
    return fail(EAGAIN);
  const FakeEvent ev = cam.config.script.front();
  cam.config.script.pop_front();
  switch (ev.kind) {
    case FakeEvent::Kind::kEagain:
      return fail(EAGAIN);
    case FakeEvent::Kind::kEnodev:
      cam.unplugged = true;
      cam.streaming = false;
      cam.failed_opens = 0;
      return fail(ENODEV);
    default:
      break;
  }
  if (cam.queue.empty()) {
    ++starved_;
    return fail(EINVAL);
  }
  const std::uint32_t index = cam.queue.front();
  cam.queue.pop_front();
  ++cam.dequeued;
  b->index = index;
  b->flags =
      cam.config.monotonic ? V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC : V4L2_BUF_FLAG_TIMESTAMP_UNKNOWN;
  b->field = V4L2_FIELD_NONE;
  b->sequence = ev.sequence;
  b->timestamp.tv_sec = static_cast<time_t>(ev.t_ns / kNsPerS);
  b->timestamp.tv_usec = static_cast<suseconds_t>((ev.t_ns % kNsPerS) / kNsPerUs);
  b->length = static_cast<std::uint32_t>(cam.buffers[index].size());
  b->m.offset = static_cast<std::uint32_t>(index * kOffsetStep);
  if (ev.kind == FakeEvent::Kind::kEio) {
    b->bytesused = 0;
    return fail(EIO);
  }
  fill(cam, index, ev.sequence, b->bytesused);
  if (ev.kind == FakeEvent::Kind::kErrorFlag) b->flags |= V4L2_BUF_FLAG_ERROR;
  return 0;
}

int FakeV4l2Device::ioctl(int fd, unsigned long request, void* arg) {
  Camera* cam = cameraOf(fd);
  if (cam == nullptr) return fail(EBADF);
  if (cam->unplugged) return fail(ENODEV);
  switch (request) {
    case VIDIOC_QUERYCAP: {
      auto* c = static_cast<v4l2_capability*>(arg);
      *c = {};
      std::strncpy(reinterpret_cast<char*>(c->driver), "svslam-fake", sizeof(c->driver) - 1);
      const std::uint32_t caps = cam->config.capabilities
                                     ? cam->config.capabilities
                                     : (V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_STREAMING);
      c->device_caps = caps;
      c->capabilities = caps | V4L2_CAP_DEVICE_CAPS;
      return 0;
    }
    case VIDIOC_S_FMT:
    case VIDIOC_G_FMT: {
      auto* f = static_cast<v4l2_format*>(arg);
      if (f->type != V4L2_BUF_TYPE_VIDEO_CAPTURE) return fail(EINVAL);
      if (request == VIDIOC_S_FMT) {
        if (cam->streaming) return fail(EBUSY);
        const FakeCameraConfig& c = cam->config;
        cam->width = c.granted_width ? c.granted_width : f->fmt.pix.width;
        cam->height = c.granted_height ? c.granted_height : f->fmt.pix.height;
        cam->fourcc = c.granted_fourcc ? c.granted_fourcc : f->fmt.pix.pixelformat;
        if (cam->fourcc == V4L2_PIX_FMT_MJPEG) {
          cam->bytes_per_line = 0;
          cam->size_image = cam->width * cam->height * 2 + 4096;
        } else {
          const std::uint32_t bpp = cam->fourcc == V4L2_PIX_FMT_YUYV ? 2 : 1;
          cam->bytes_per_line = cam->width * bpp + c.row_padding;
          cam->size_image = cam->bytes_per_line * cam->height;
        }
      }
      f->fmt.pix.width = cam->width;
      f->fmt.pix.height = cam->height;
      f->fmt.pix.pixelformat = cam->fourcc;
      f->fmt.pix.field = V4L2_FIELD_NONE;
      f->fmt.pix.bytesperline = cam->bytes_per_line;
      f->fmt.pix.sizeimage = cam->size_image;
      return 0;
    }
    case VIDIOC_S_PARM: {
      auto* p = static_cast<v4l2_streamparm*>(arg);
      p->parm.capture.capability = V4L2_CAP_TIMEPERFRAME;
      return 0;  // accepts any rate as asked
    }
    case VIDIOC_REQBUFS: {
      auto* r = static_cast<v4l2_requestbuffers*>(arg);
      if (r->memory != V4L2_MEMORY_MMAP) return fail(EINVAL);
      if (cam->streaming) return fail(EBUSY);
      r->count = std::min(r->count, cam->config.max_buffers);
      cam->buffers.assign(r->count, std::vector<std::uint8_t>(cam->size_image));
      cam->queue.clear();
      return 0;
    }
    case VIDIOC_QUERYBUF:
    case VIDIOC_QBUF: {
      auto* b = static_cast<v4l2_buffer*>(arg);
      if (b->index >= cam->buffers.size()) return fail(EINVAL);
      if (request == VIDIOC_QBUF) {
        if (std::find(cam->queue.begin(), cam->queue.end(), b->index) != cam->queue.end())
          return fail(EINVAL);  // already queued
        cam->queue.push_back(b->index);
        ++cam->queued_total;
        return 0;
      }
      b->length = static_cast<std::uint32_t>(cam->buffers[b->index].size());
      b->m.offset = static_cast<std::uint32_t>(b->index * kOffsetStep);
      return 0;
    }
    case VIDIOC_DQBUF:
      return dqbuf(*cam, arg);
    case VIDIOC_STREAMON:
      if (cam->buffers.empty()) return fail(EINVAL);
      cam->streaming = true;
      return 0;
    case VIDIOC_STREAMOFF:
      cam->streaming = false;
      cam->queue.clear();
      return 0;
    default:
      return fail(ENOTTY);
  }
}

void* FakeV4l2Device::mmap(void* addr, std::size_t length, int prot, int flags, int fd,
                           off_t offset) {
  (void)addr;
  (void)prot;
  (void)flags;
  Camera* cam = cameraOf(fd);
  const auto index = static_cast<std::size_t>(offset / kOffsetStep);
  if (cam == nullptr || offset % kOffsetStep != 0 || index >= cam->buffers.size() ||
      length > cam->buffers[index].size()) {
    errno = EINVAL;
    return MAP_FAILED;
  }
  ++mapped_;
  return cam->buffers[index].data();
}

int FakeV4l2Device::munmap(void* addr, std::size_t length) {
  (void)length;
  if (addr == nullptr || mapped_ == 0) return fail(EINVAL);
  --mapped_;
  return 0;
}

int FakeV4l2Device::poll(struct pollfd* fds, nfds_t nfds, int timeout_ms) {
  (void)timeout_ms;
  if (poll_sleep_us_ > 0) std::this_thread::sleep_for(std::chrono::microseconds(poll_sleep_us_));
  int ready = 0;
  for (nfds_t i = 0; i < nfds; ++i) {
    fds[i].revents = 0;
    Camera* cam = cameraOf(fds[i].fd);
    if (cam == nullptr) {
      fds[i].revents = POLLNVAL;
    } else if (cam->unplugged) {
      fds[i].revents = POLLERR;
    } else if (!cam->config.script.empty()) {
      const FakeEvent& ev = cam->config.script.front();
      if (ev.kind == FakeEvent::Kind::kTimeout) {
        cam->config.script.pop_front();
      } else {
        fds[i].revents = ev.kind == FakeEvent::Kind::kEnodev ? POLLERR : POLLIN;
      }
    }
    if (fds[i].revents) ++ready;
  }
  return ready;
}

}  // namespace svslam::drivers::testing
