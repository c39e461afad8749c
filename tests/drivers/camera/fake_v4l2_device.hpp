#pragma once
// FakeV4l2Device: a scripted V4L2 driver behind the V4l2Device interface, for tests.
//
// Each camera is registered under a path with a base image; frames are generated on demand in
// the negotiated format (GREY with padded rows, YUYV, MJPEG via cv::imencode), content
// expectedFrame(base, sequence) = (base + sequence) mod 256 so a test can tell frames apart.
// A camera's script is a queue of events consumed by poll() / VIDIOC_DQBUF:
//   frame(t_ns, seq)  poll ready; DQBUF fills the oldest queued buffer (timestamp MONOTONIC)
//   eagain()          poll ready; DQBUF fails with EAGAIN
//   eio()             poll ready; DQBUF dequeues the oldest buffer and fails with EIO
//   errorFlag(t, s)   poll ready; DQBUF returns a buffer flagged V4L2_BUF_FLAG_ERROR
//   enodev()          the camera is unplugged: poll reports POLLERR; DQBUF and every ioctl
//                     after fail with ENODEV; open() fails with absent_errno
//   timeout()         poll returns 0 once
// An empty script behaves like timeout(). DQBUF with no queued buffer fails with EINVAL and
// counts starved() (the capture forgot to requeue). Several fds, one stream per camera.
// Plugging back: after replug_after_opens failed open() calls of an unplugged camera the next
// open() finds it back (the script goes on); plug() does it at once, unplug() like enodev().
#include <cerrno>
#include <cstdint>
#include <deque>
#include <map>
#include <string>
#include <vector>

#include "core/image.hpp"
#include "core/time.hpp"
#include "drivers/camera/v4l2_device.hpp"

namespace svslam::drivers::testing {

struct FakeEvent {
  enum class Kind { kFrame, kEagain, kEio, kErrorFlag, kEnodev, kTimeout };
  Kind kind = Kind::kFrame;
  TimeNs t_ns = 0;
  std::uint32_t sequence = 0;
  static FakeEvent frame(TimeNs t_ns, std::uint32_t seq) { return {Kind::kFrame, t_ns, seq}; }
  static FakeEvent eagain() { return {Kind::kEagain, 0, 0}; }
  static FakeEvent eio() { return {Kind::kEio, 0, 0}; }
  static FakeEvent errorFlag(TimeNs t_ns, std::uint32_t seq) {
    return {Kind::kErrorFlag, t_ns, seq};
  }
  static FakeEvent enodev() { return {Kind::kEnodev, 0, 0}; }
  static FakeEvent timeout() { return {Kind::kTimeout, 0, 0}; }
};

struct FakeCameraConfig {
  ImageU8 base;                     // the scene (full frame for side-by-side)
  std::vector<ImageU8> bases;       // when not empty: frame `seq` shows bases[seq % size]
  std::uint32_t granted_width = 0;  // S_FMT answers with this width (0 = as asked)
  std::uint32_t granted_height = 0;
  std::uint32_t granted_fourcc = 0;  // 0 = as asked
  std::uint32_t row_padding = 0;     // extra bytes per line for GREY / YUYV
  std::uint32_t capabilities = 0;    // 0 = VIDEO_CAPTURE | STREAMING
  std::uint32_t max_buffers = 8;     // REQBUFS grants min(asked, this)
  bool monotonic = true;             // V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC on buffers
  int replug_after_opens = -1;       // failed opens while unplugged before it is back; -1 never
  int absent_errno = ENOENT;         // open() of an unplugged camera (the node is gone)
  std::int64_t freeze_from_sequence = -1;  // >= 0: frames from this sequence on show its image
  std::deque<FakeEvent> script;
};

// (base(x, y) + sequence) mod 256.
ImageU8 expectedFrame(const ImageU8& base, std::uint32_t sequence);
// A textured test image (smooth gradients plus blobs; JPEG-friendly).
ImageU8 testPattern(int width, int height, int seed = 0);

class FakeV4l2Device final : public V4l2Device {
 public:
  // Registers (or replaces) the camera at `path`.
  void addCamera(const std::string& path, FakeCameraConfig config);
  FakeCameraConfig& camera(const std::string& path) { return cams_.at(path).config; }

  int open(const std::string& path, int flags) override;
  int close(int fd) override;
  int ioctl(int fd, unsigned long request, void* arg) override;
  void* mmap(void* addr, std::size_t length, int prot, int flags, int fd, off_t offset) override;
  int munmap(void* addr, std::size_t length) override;
  int poll(struct pollfd* fds, nfds_t nfds, int timeout_ms) override;

  int openFds() const { return static_cast<int>(fds_.size()); }
  int mappedBuffers() const { return mapped_; }
  int starved() const { return starved_; }
  bool streaming(const std::string& path) const { return cams_.at(path).streaming; }
  int dequeued(const std::string& path) const { return cams_.at(path).dequeued; }
  // open() calls for `path`, successful or not.
  int opens(const std::string& path) const { return cams_.at(path).opens; }
  bool unplugged(const std::string& path) const { return cams_.at(path).unplugged; }
  void unplug(const std::string& path);
  void plug(const std::string& path);
  // Every poll() sleeps this long first (a driver whose buffers take time), us.
  void setPollSleepUs(int us) { poll_sleep_us_ = us; }
  int queued(const std::string& path) const { return cams_.at(path).queued_total; }

 private:
  struct Camera {
    FakeCameraConfig config;
    std::uint32_t width = 0, height = 0, fourcc = 0, bytes_per_line = 0, size_image = 0;
    std::vector<std::vector<std::uint8_t>> buffers;
    std::deque<std::uint32_t> queue;  // buffer indices owned by the driver, oldest first
    bool streaming = false;
    bool unplugged = false;
    int failed_opens = 0;  // since the unplug
    int opens = 0;
    int dequeued = 0;
    int queued_total = 0;
  };
  Camera* cameraOf(int fd);
  int dqbuf(Camera& cam, void* arg);
  void fill(Camera& cam, std::uint32_t index, std::uint32_t sequence, std::uint32_t& bytes_used);

  std::map<std::string, Camera> cams_;
  std::map<int, std::string> fds_;
  int next_fd_ = 100;
  int mapped_ = 0;
  int starved_ = 0;
  int poll_sleep_us_ = 0;
};

}  // namespace svslam::drivers::testing
