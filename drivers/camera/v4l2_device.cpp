// The real V4L2 system calls (see v4l2_device.hpp).
#include "drivers/camera/v4l2_device.hpp"

#include <fcntl.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>

namespace svslam::drivers {

int SystemV4l2Device::open(const std::string& path, int flags) {
  return ::open(path.c_str(), flags | O_CLOEXEC);
}

int SystemV4l2Device::close(int fd) { return ::close(fd); }

int SystemV4l2Device::ioctl(int fd, unsigned long request, void* arg) {
  int r;
  do {
    r = ::ioctl(fd, request, arg);
  } while (r == -1 && errno == EINTR);
  return r;
}

void* SystemV4l2Device::mmap(void* addr, std::size_t length, int prot, int flags, int fd,
                             off_t offset) {
  return ::mmap(addr, length, prot, flags, fd, offset);
}

int SystemV4l2Device::munmap(void* addr, std::size_t length) { return ::munmap(addr, length); }

int SystemV4l2Device::poll(struct pollfd* fds, nfds_t nfds, int timeout_ms) {
  return ::poll(fds, nfds, timeout_ms);
}

V4l2Device& systemV4l2Device() {
  static SystemV4l2Device device;
  return device;
}

}  // namespace svslam::drivers
