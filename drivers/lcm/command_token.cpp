#include "drivers/lcm/command_token.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace svslam::drivers {

Result<std::string> readCommandToken(const std::string& path) {
  const std::string what = "command token file '" + path + "'";
  if (path.empty()) return Status::invalidArgument("command token file: no path given");
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW);
  if (fd < 0) return Status::ioError(what + ": cannot open (" + std::strerror(errno) + ")");
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    return Status::invalidArgument(what + ": not a regular file");
  }
  if ((st.st_mode & 077) != 0) {
    ::close(fd);
    char mode[8];
    std::snprintf(mode, sizeof mode, "%04o", static_cast<unsigned>(st.st_mode & 07777));
    return Status::invalidArgument(what + ": mode " + mode +
                                   " lets group or others access it; it must be readable by "
                                   "the service alone (chmod 0600)");
  }
  std::string token;
  char buf[512];
  for (;;) {
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      const int err = errno;
      ::close(fd);
      return Status::ioError(what + ": read failed (" + std::strerror(err) + ")");
    }
    if (n == 0) break;
    token.append(buf, static_cast<std::size_t>(n));
    if (token.size() > kMaxCommandTokenBytes + 64) break;
  }
  ::close(fd);
  while (!token.empty() && (token.back() == '\n' || token.back() == '\r' || token.back() == ' ' ||
                            token.back() == '\t'))
    token.pop_back();
  if (token.empty()) return Status::invalidArgument(what + ": empty (no token in it)");
  if (token.size() > kMaxCommandTokenBytes)
    return Status::invalidArgument(what + ": token longer than " +
                                   std::to_string(kMaxCommandTokenBytes) + " bytes");
  return token;
}

}  // namespace svslam::drivers
