#pragma once
// V4l2Device: the handful of system calls a V4L2 capture needs, behind a virtual interface so
// tests can put a scripted fake driver behind them (the way Chromium's capture code does).
// Every method has the contract of the system call of the same name: on failure it returns -1
// (mmap: MAP_FAILED) and sets errno.
#include <poll.h>
#include <sys/types.h>

#include <cstddef>
#include <string>

namespace svslam::drivers {

class V4l2Device {
 public:
  virtual ~V4l2Device() = default;
  virtual int open(const std::string& path, int flags) = 0;
  virtual int close(int fd) = 0;
  virtual int ioctl(int fd, unsigned long request, void* arg) = 0;
  virtual void* mmap(void* addr, std::size_t length, int prot, int flags, int fd, off_t offset) = 0;
  virtual int munmap(void* addr, std::size_t length) = 0;
  virtual int poll(struct pollfd* fds, nfds_t nfds, int timeout_ms) = 0;
};

// The real kernel interface; ioctl is retried while it fails with EINTR.
class SystemV4l2Device final : public V4l2Device {
 public:
  int open(const std::string& path, int flags) override;
  int close(int fd) override;
  int ioctl(int fd, unsigned long request, void* arg) override;
  void* mmap(void* addr, std::size_t length, int prot, int flags, int fd, off_t offset) override;
  int munmap(void* addr, std::size_t length) override;
  int poll(struct pollfd* fds, nfds_t nfds, int timeout_ms) override;
};

// A process-wide SystemV4l2Device (stateless, so sharing it is safe).
V4l2Device& systemV4l2Device();

}  // namespace svslam::drivers
