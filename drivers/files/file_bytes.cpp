#include "drivers/files/file_bytes.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

namespace svslam::drivers {

namespace fs = std::filesystem;

Result<Bytes> readFileBytes(const std::string& path, const char* what) {
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (!fs::exists(st)) return Status::notFound(std::string(what) + " does not exist: " + path);
  if (fs::is_directory(st)) {
    return Status::invalidArgument(std::string(what) + " is a directory, not a file: " + path);
  }
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (f == nullptr) {
    return Status::ioError("cannot open " + path + " for reading: " + std::strerror(errno));
  }
  Bytes bytes;
  unsigned char chunk[1 << 16];
  std::size_t got = 0;
  while ((got = std::fread(chunk, 1, sizeof(chunk), f)) > 0)
    bytes.insert(bytes.end(), chunk, chunk + got);
  const bool failed = std::ferror(f) != 0;
  std::fclose(f);
  if (failed) return Status::ioError("reading " + path + " failed");
  if (bytes.empty())
    return Status::invalidArgument(std::string(what) + " is empty (0 bytes): " + path);
  return bytes;
}

Status writeFileAtomically(const std::string& path, const void* data, std::size_t n) {
  const std::string tmp = path + ".tmp";
  std::error_code ec;
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (f == nullptr) {
    const std::string why = std::strerror(errno);
    fs::remove(tmp, ec);
    return Status::ioError("cannot write " + path + ": cannot create " + tmp + ": " + why);
  }
  const bool wrote = std::fwrite(data, 1, n, f) == n && std::fflush(f) == 0;
  std::string why = wrote ? std::string() : std::strerror(errno);
  const bool closed = std::fclose(f) == 0;
  if (!closed && why.empty()) why = std::strerror(errno);
  if (!wrote || !closed) {
    fs::remove(tmp, ec);
    return Status::ioError("cannot write " + path + ": writing " + tmp + " failed" +
                           (why.empty() ? std::string() : ": " + why));
  }
  fs::rename(tmp, path, ec);
  if (ec) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
    return Status::ioError("cannot write " + path + ": cannot rename " + tmp +
                           " to it: " + ec.message());
  }
  return Status::ok();
}

}  // namespace svslam::drivers
