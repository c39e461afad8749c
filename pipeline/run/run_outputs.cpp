#include "pipeline/run/run_outputs.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <system_error>

namespace svslam::run {

Status clearRunOutputs(const std::string& dir) {
  namespace fs = std::filesystem;
  for (const char* name : files::kAll) {
    for (const std::string& file : {std::string(name), std::string(name) + ".tmp"}) {
      const fs::path path = fs::path(dir) / file;
      std::error_code ec;
      const fs::file_status st = fs::symlink_status(path, ec);
      if (ec || !fs::exists(st) || fs::is_directory(st)) continue;
      if (!fs::remove(path, ec) || ec)
        return Status::ioError("cannot remove '" + path.string() +
                               "' of an earlier run: " + (ec ? ec.message() : "not removed"));
    }
  }
  return Status::ok();
}

AppendFile::~AppendFile() { (void)close(); }

Status AppendFile::open(const std::string& path) {
  (void)close();
  error_ = Status::ok();
  whole_bytes_ = 0;
  fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd_ < 0) return Status::ioError("cannot create '" + path + "': " + std::strerror(errno));
  path_ = path;
  return Status::ok();
}

Status AppendFile::append(const char* data, std::size_t n) {
  if (fd_ < 0) return Status::failedPrecondition("'" + path_ + "' is not open");
  if (!error_) return error_;
  std::size_t done = 0;
  while (done < n) {
    const ssize_t w = ::write(fd_, data + done, n - done);
    if (w > 0) {
      done += static_cast<std::size_t>(w);
      continue;
    }
    if (w < 0 && errno == EINTR) continue;
    const int err = w < 0 ? errno : EIO;
    // Cut the partial line off: the file ends with its last whole line.
    const bool cut = ::ftruncate(fd_, static_cast<off_t>(whole_bytes_)) == 0 &&
                     ::lseek(fd_, 0, SEEK_END) == static_cast<off_t>(whole_bytes_);
    error_ = Status::ioError("cannot write '" + path_ + "': " + std::strerror(err) +
                             (cut ? " (it keeps the lines written before)" : ""));
    return error_;
  }
  whole_bytes_ += static_cast<std::int64_t>(n);
  return Status::ok();
}

Status AppendFile::close() {
  if (fd_ < 0) return Status::ok();
  const int r = ::close(fd_);
  fd_ = -1;
  if (r != 0) return Status::ioError("cannot close '" + path_ + "': " + std::strerror(errno));
  return Status::ok();
}

Status TrajectoryWriter::open(const std::string& kitti_path, const std::string& tum_path) {
  (void)close();
  if (Status s = kitti_.open(kitti_path); !s) return s;
  if (!tum_path.empty()) return tum_.open(tum_path);
  return Status::ok();
}

Status TrajectoryWriter::append(TimeNs t_ns, const Eigen::Isometry3d& T) {
  if (!kitti_.isOpen()) return Status::failedPrecondition("trajectory writer is not open");
  const Eigen::Matrix4d M = T.matrix();
  if (!M.allFinite()) return Status::invalidArgument("refusing to write a non-finite pose");
  char line[512];  // 12 numbers of at most 16 characters, and their separators
  int n = 0;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c)
      n += std::snprintf(line + n, sizeof line - static_cast<std::size_t>(n), "%s%.9e",
                         r == 0 && c == 0 ? "" : " ", M(r, c));
  n += std::snprintf(line + n, sizeof line - static_cast<std::size_t>(n), "\n");
  if (Status s = kitti_.append(line, static_cast<std::size_t>(n)); !s) return s;
  if (tum_.isOpen()) {
    const Eigen::Quaterniond q(T.rotation());
    const Eigen::Vector3d t = T.translation();
    n = std::snprintf(line, sizeof line, "%.9f %.9f %.9f %.9f %.9f %.9f %.9f %.9f\n",
                      static_cast<double>(t_ns) * 1e-9, t.x(), t.y(), t.z(), q.x(), q.y(), q.z(),
                      q.w());
    if (n < 0 || n >= static_cast<int>(sizeof line))
      return Status::invalidArgument("trajectory line too long for '" + tum_.path() + "'");
    if (Status s = tum_.append(line, static_cast<std::size_t>(n)); !s) return s;
  }
  return Status::ok();
}

Status TrajectoryWriter::close() {
  const Status a = kitti_.close();
  const Status b = tum_.close();
  return a ? b : a;
}

Status LineWriter::open(const std::string& path) {
  (void)close();
  return file_.open(path);
}

Status LineWriter::append(const std::string& line) {
  if (!file_.isOpen()) return Status::failedPrecondition("line writer is not open");
  buf_.assign(line);  // keeps its capacity: no allocation once warm
  buf_ += '\n';
  return file_.append(buf_.data(), buf_.size());
}

Status LineWriter::close() { return file_.close(); }

Status writeLandmarksPly(const std::string& path, const std::vector<PlyLandmark>& landmarks) {
  std::size_t n = 0;
  for (const auto& l : landmarks) n += l.p_world.allFinite() && l.sigma_m.allFinite() ? 1 : 0;
  std::ostringstream ss;
  ss << "ply\nformat ascii 1.0\ncomment svslam landmarks: world frame = first left camera, "
        "metres; sigma = 1-sigma radii along x, y, z\n"
     << "element vertex " << n << "\n"
     << "property float x\nproperty float y\nproperty float z\n"
     << "property float sigma_x\nproperty float sigma_y\nproperty float sigma_z\n"
     << "property int id\nproperty uchar active\nproperty int observations\nend_header\n";
  char buf[256];
  for (const auto& l : landmarks) {
    if (!l.p_world.allFinite() || !l.sigma_m.allFinite()) continue;
    std::snprintf(buf, sizeof buf, "%.6f %.6f %.6f %.6f %.6f %.6f %d %d %d\n", l.p_world.x(),
                  l.p_world.y(), l.p_world.z(), l.sigma_m.x(), l.sigma_m.y(), l.sigma_m.z(), l.id,
                  l.active ? 1 : 0, l.observations);
    ss << buf;
  }
  return writeFileAtomic(path, ss.str());
}

StageTimes::StageTimes(std::size_t capacity) : capacity_(std::max<std::size_t>(capacity, 1)) {}

StageTimes::Samples& StageTimes::stage(std::string_view name) {
  auto it = samples_.find(name);
  if (it == samples_.end()) {
    order_.emplace_back(name);
    it = samples_.emplace(std::string(name), Samples{}).first;
    it->second.ring.resize(capacity_);
  }
  return it->second;
}

void StageTimes::push(Samples& s, double ms) const {
  s.ring[s.next] = ms;
  s.next = (s.next + 1) % capacity_;
  s.kept_n = std::min(s.kept_n + 1, capacity_);
  s.max_ms = s.count == 0 ? ms : std::max(s.max_ms, ms);
  ++s.count;
}

void StageTimes::add(std::string_view stage_name, double ms) { push(stage(stage_name), ms); }

std::vector<double> StageTimes::Samples::kept() const {
  if (kept_n < ring.size())  // not wrapped yet: slots 0 .. kept_n - 1
    return {ring.begin(), ring.begin() + static_cast<std::ptrdiff_t>(kept_n)};
  std::vector<double> v(ring.begin() + static_cast<std::ptrdiff_t>(next), ring.end());
  v.insert(v.end(), ring.begin(), ring.begin() + static_cast<std::ptrdiff_t>(next));
  return v;
}

void StageTimes::merge(const StageTimes& other) {
  for (const std::string& name : other.order_) {
    const Samples& theirs = other.samples_.find(name)->second;
    Samples& mine = stage(name);
    for (const double ms : theirs.kept()) push(mine, ms);
    // Samples `other` no longer keeps still count, and its max covers them.
    mine.count += theirs.count - static_cast<std::int64_t>(theirs.kept_n);
    if (theirs.count > 0) mine.max_ms = std::max(mine.max_ms, theirs.max_ms);
  }
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const double rank = std::ceil(p / 100.0 * static_cast<double>(v.size()));
  const std::size_t i =
      static_cast<std::size_t>(std::clamp(rank, 1.0, static_cast<double>(v.size())));
  return v[i - 1];
}

double StageTimes::median(const std::string& name) const {
  auto it = samples_.find(name);
  return it == samples_.end() ? NAN : percentile(it->second.kept(), 50);
}

std::string StageTimes::json() const {
  std::ostringstream ss;
  ss.setf(std::ios::fixed);
  ss.precision(3);
  ss << "{";
  bool first = true;
  for (const auto& name : order_) {
    const Samples& st = samples_.find(name)->second;
    const std::vector<double> v = st.kept();
    ss << (first ? "" : ", ") << "\"" << name << "\": {\"p50_ms\": " << percentile(v, 50)
       << ", \"p99_ms\": " << percentile(v, 99) << ", \"max_ms\": " << st.max_ms
       << ", \"count\": " << st.count << "}";
    first = false;
  }
  ss << "}";
  return ss.str();
}

Status writeFileAtomic(const std::string& path, const std::string& text) {
  const std::string tmp = path + ".tmp";
  std::FILE* f = std::fopen(tmp.c_str(), "w");
  if (!f) return Status::ioError("cannot create '" + tmp + "': " + std::strerror(errno));
  errno = 0;
  const bool wrote =
      std::fwrite(text.data(), 1, text.size(), f) == text.size() && std::fflush(f) == 0;
  const int write_err = errno;
  errno = 0;
  const bool closed = std::fclose(f) == 0;
  const int close_err = errno;
  if (!wrote || !closed) {
    std::remove(tmp.c_str());
    const int err = !wrote ? write_err : close_err;
    return Status::ioError("cannot write '" + path +
                           "': " + (err != 0 ? std::strerror(err) : "write failed"));
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    return Status::ioError("cannot rename '" + tmp + "' to '" + path +
                           "': " + std::strerror(errno));
  }
  return Status::ok();
}

}  // namespace svslam::run
