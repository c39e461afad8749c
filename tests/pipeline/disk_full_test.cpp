// `svslam run` when its outputs cannot be written: a file size limit (RLIMIT_FSIZE set in the
// child before exec: writes beyond it fail with EFBIG, svslam ignores SIGXFSZ) that the first
// file written already exceeds, one that a per-frame file reaches mid-run, and one that only the
// files written at the end exceed; then a full disk (a small tmpfs in a private mount namespace,
// ENOSPC; skipped where unshare is not permitted). Each time: exit 1 (no crash, no hang), the
// error names the file that failed first and the system's reason, every file written before is
// byte-identical to an unlimited run's (or, for a per-frame file, a prefix of whole lines), no
// temporary file is left, and no NaN is written.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include "cli_helpers.hpp"

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using svslam::test::slurp;

namespace {

const char* kSource = "synthetic:width=320,height=240,frames=12";
// Written one line per frame while the run goes, in this order per frame.
const char* kPerFrame[] = {"trajectory_kitti.txt", "trajectory_tum.txt", "pose_covariance.txt",
                           "groundtruth_kitti.txt"};
// Written once at the end, in this order (SlamStages::finish, then the mapper's files).
const char* kAtEnd[] = {"landmarks.ply", "dem.tif",           "ortho.tif",
                        "ortho.png",     "dem_hillshade.png", "groundtruth_dem.tif"};

struct ChildResult {
  int rc = -1;  // exit code, 128 + signal, or -1 when killed after the timeout
  std::string out, err;
};

// Runs `argv` with RLIMIT_FSIZE = `limit` bytes (< 0: unlimited). Its stdout and stderr come
// back through pipes: the limit applies to any file the child writes, its log files too.
ChildResult runChild(const std::vector<std::string>& argv, long long limit,
                     std::chrono::seconds timeout = 180s) {
  int out_pipe[2], err_pipe[2];
  EXPECT_EQ(::pipe(out_pipe), 0);
  EXPECT_EQ(::pipe(err_pipe), 0);
  const pid_t pid = ::fork();
  if (pid == 0) {
    if (limit >= 0) {
      const rlimit r{static_cast<rlim_t>(limit), static_cast<rlim_t>(limit)};
      if (::setrlimit(RLIMIT_FSIZE, &r) != 0) ::_exit(126);
    }
    ::dup2(out_pipe[1], 1);
    ::dup2(err_pipe[1], 2);
    for (int fd : {out_pipe[0], out_pipe[1], err_pipe[0], err_pipe[1]}) ::close(fd);
    std::vector<char*> args;
    for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    ::execv(args[0], args.data());
    ::_exit(127);
  }
  ::close(out_pipe[1]);
  ::close(err_pipe[1]);
  ChildResult r;
  const auto t0 = std::chrono::steady_clock::now();
  pollfd fds[2] = {{out_pipe[0], POLLIN, 0}, {err_pipe[0], POLLIN, 0}};
  int open_fds = 2;
  while (open_fds > 0 && std::chrono::steady_clock::now() - t0 < timeout) {
    if (::poll(fds, 2, 200) <= 0) continue;
    for (int k = 0; k < 2; ++k) {
      if (fds[k].fd < 0 || !(fds[k].revents & (POLLIN | POLLHUP))) continue;
      char buf[4096];
      const ssize_t n = ::read(fds[k].fd, buf, sizeof buf);
      if (n > 0) {
        (k == 0 ? r.out : r.err).append(buf, static_cast<std::size_t>(n));
      } else {
        ::close(fds[k].fd);
        fds[k].fd = -1;
        --open_fds;
      }
    }
  }
  for (pollfd& f : fds)
    if (f.fd >= 0) ::close(f.fd);
  int st = 0;
  while (::waitpid(pid, &st, WNOHANG) == 0) {
    if (std::chrono::steady_clock::now() - t0 > timeout) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &st, 0);
      return r;  // rc -1: it hung
    }
    std::this_thread::sleep_for(20ms);
  }
  r.rc = svslam::test::exitCode(st);
  return r;
}

ChildResult runSvslam(const fs::path& out, long long limit) {
  return runChild({SVSLAM_CLI, "run", "--source", kSource, "--out", out.string()}, limit);
}

// The first line of `err` that reports a write failure.
std::string firstFailure(const std::string& err) {
  const std::size_t at = err.find("cannot write");
  if (at == std::string::npos) return "";
  const std::size_t end = err.find_first_of(";\n", at);
  return err.substr(at, end == std::string::npos ? std::string::npos : end - at);
}

int countLines(const std::string& s) {
  int n = 0;
  for (char c : s) n += c == '\n';
  return n;
}

class DiskFull : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(svslam::test::freshTestDir("svslam_diskfull_"));
    const ChildResult r = runSvslam(*dir_ / "reference", -1);
    ASSERT_EQ(r.rc, 0) << r.err;
    reference_ = new std::map<std::string, std::string>;
    for (const auto& e : fs::directory_iterator(*dir_ / "reference"))
      (*reference_)[e.path().filename().string()] = slurp(e.path());
  }
  static void TearDownTestSuite() {
    fs::remove_all(*dir_);
    delete dir_;
    delete reference_;
  }
  static const std::string& ref(const std::string& name) { return reference_->at(name); }
  static std::size_t refSize(const std::string& name) { return ref(name).size(); }

  // What every failed run must show: exit 1, the first failure naming `file` in `out` and
  // `reason`, every output either absent, byte-identical to the reference, or (per-frame
  // files) a prefix of it made of whole lines; no temporary file; no NaN in stats.json.
  // `cut_short`: the failure stopped the run before its last frame, so the map written at the
  // end is the map of fewer frames: landmarks.ply must then be a complete PLY (as many vertex
  // lines as its header says), not the reference's bytes.
  static void expectCleanFailure(const ChildResult& r, const fs::path& out, const std::string& file,
                                 const std::string& reason, bool cut_short = false) {
    ASSERT_EQ(r.rc, 1) << "stderr:\n" << r.err;
    const std::string first = firstFailure(r.err);
    EXPECT_NE(first.find((out / file).string()), std::string::npos) << r.err;
    EXPECT_NE(first.find(reason), std::string::npos) << r.err;
    EXPECT_EQ(r.out, "");  // no success summary
    for (const auto& e : fs::directory_iterator(out)) {
      const std::string name = e.path().filename().string();
      EXPECT_EQ(name.find(".tmp"), std::string::npos) << "temporary file left: " << name;
      const std::string got = slurp(e.path());
      if (name == "stats.json") {
        EXPECT_EQ(got.find("nan"), std::string::npos) << got;
        EXPECT_EQ(got.back(), '\n');
        EXPECT_NE(got.find("\"error\": \"cannot write"), std::string::npos) << got;
        continue;
      }
      if (cut_short && name == "landmarks.ply") {
        const std::size_t header_end = got.find("end_header\n");
        const std::size_t count_at = got.find("element vertex ");
        ASSERT_NE(header_end, std::string::npos) << got;
        ASSERT_NE(count_at, std::string::npos) << got;
        const int vertices = std::stoi(got.substr(count_at + 15));
        EXPECT_EQ(countLines(got.substr(header_end + 11)), vertices) << got;
        EXPECT_EQ(got.back(), '\n');
        continue;
      }
      ASSERT_TRUE(reference_->count(name)) << name;
      const std::string& want = ref(name);
      const bool per_frame =
          std::find_if(std::begin(kPerFrame), std::end(kPerFrame),
                       [&](const char* f) { return name == f; }) != std::end(kPerFrame);
      if (per_frame) {
        EXPECT_EQ(want.compare(0, got.size(), got), 0)
            << name << " is not a prefix of the reference";
        EXPECT_TRUE(got.empty() || got.back() == '\n') << name << " ends in a partial line";
      } else {
        EXPECT_TRUE(got == want) << name << " differs from the reference (" << got.size()
                                 << " bytes, reference " << want.size() << ")";
      }
    }
  }

  static fs::path* dir_;
  static std::map<std::string, std::string>* reference_;
};

fs::path* DiskFull::dir_ = nullptr;
std::map<std::string, std::string>* DiskFull::reference_ = nullptr;

TEST_F(DiskFull, TheReferenceRunWritesEveryFile) {
  for (const char* f : kPerFrame) EXPECT_EQ(countLines(ref(f)), 12) << f;
  for (const char* f : kAtEnd) EXPECT_GT(refSize(f), 0u) << f;
}

TEST_F(DiskFull, FirstFileWrittenFails) {
  ASSERT_GT(refSize("trajectory_kitti.txt") / 12, 100u);  // its first line exceeds the limit
  const fs::path out = *dir_ / "limit_100";
  const ChildResult r = runSvslam(out, 100);
  expectCleanFailure(r, out, "trajectory_kitti.txt", "File too large");
  EXPECT_EQ(slurp(out / "trajectory_kitti.txt"), "");  // the partial line was cut off
  EXPECT_FALSE(fs::exists(out / "stats.json"));        // larger than 100 bytes too
  EXPECT_NE(r.err.find("then cannot write '" + (out / "stats.json").string() + "'"),
            std::string::npos)
      << r.err;
}

TEST_F(DiskFull, PerFrameFileFailsMidRunKeepingWholeLines) {
  // Room for every trajectory line; pose_covariance.txt (three times longer lines) fills up.
  const long long limit = static_cast<long long>(refSize("trajectory_kitti.txt"));
  ASSERT_GT(refSize("pose_covariance.txt"), static_cast<std::size_t>(limit));
  const fs::path out = *dir_ / "limit_mid";
  const ChildResult r = runSvslam(out, limit);
  expectCleanFailure(r, out, "pose_covariance.txt", "File too large", /*cut_short=*/true);
  const int cov = countLines(slurp(out / "pose_covariance.txt"));
  EXPECT_GT(cov, 0);
  EXPECT_LT(cov, 12);
  // Per frame: the trajectory lines, then the covariance line failed: one trajectory line more.
  EXPECT_EQ(countLines(slurp(out / "trajectory_kitti.txt")), cov + 1);
  EXPECT_EQ(countLines(slurp(out / "groundtruth_kitti.txt")), cov);
}

TEST_F(DiskFull, LaterFileFailsEarlierFilesIntact) {
  std::size_t limit = 0;
  for (const char* f : kPerFrame) limit = std::max(limit, refSize(f));
  // The first file written at the end that does not fit.
  std::string first;
  for (const char* f : kAtEnd)
    if (first.empty() && refSize(f) > limit) first = f;
  ASSERT_FALSE(first.empty()) << "every file fits in " << limit << " bytes: no late failure";
  const fs::path out = *dir_ / "limit_late";
  const ChildResult r = runSvslam(out, static_cast<long long>(limit));
  expectCleanFailure(r, out, first, "File too large");
  for (const char* f : kPerFrame)  // complete, byte for byte
    EXPECT_TRUE(slurp(out / f) == ref(f)) << f;
  for (const char* f : kAtEnd) {
    if (refSize(f) > limit) {
      EXPECT_FALSE(fs::exists(out / f)) << f << " exceeds the limit";
    }
    if (std::string(f) == first) break;
    EXPECT_TRUE(slurp(out / f) == ref(f)) << f << ", written before " << first;
  }
}

TEST_F(DiskFull, NoSpaceLeftOnDevice) {
  if (std::system("unshare -rm true >/dev/null 2>&1") != 0)
    GTEST_SKIP() << "unshare -rm is not permitted here: no private tmpfs to fill";
  // A 24 KiB tmpfs (6 pages) in a private mount namespace; the outputs are copied out.
  const fs::path mnt = *dir_ / "tmpfs", copy = *dir_ / "enospc";
  fs::create_directories(mnt);
  const std::string cmd = "mount -t tmpfs -o size=24k none " + mnt.string() + " && " + SVSLAM_CLI +
                          " run --source " + kSource + " --out " + (mnt / "out").string() +
                          "; rc=$?; cp -r " + (mnt / "out").string() + " " + copy.string() +
                          "; exit $rc";
  const ChildResult r = runChild({"/usr/bin/unshare", "-rm", "/bin/sh", "-c", cmd}, -1);
  ASSERT_EQ(r.rc, 1) << r.err;
  const std::string first = firstFailure(r.err);
  EXPECT_NE(first.find("No space left on device"), std::string::npos) << r.err;
  EXPECT_NE(first.find((mnt / "out").string() + "/"), std::string::npos) << r.err;
  for (const auto& e : fs::directory_iterator(copy)) {
    const std::string name = e.path().filename().string();
    EXPECT_EQ(name.find(".tmp"), std::string::npos) << name;
    const std::string got = slurp(e.path());
    if (name == "stats.json") {
      EXPECT_EQ(got.find("nan"), std::string::npos) << got;
      continue;
    }
    ASSERT_TRUE(reference_->count(name)) << name;
    EXPECT_EQ(ref(name).compare(0, got.size(), got), 0) << name;  // whole or a prefix
    EXPECT_TRUE(got.empty() || got.back() == '\n' || got == ref(name)) << name;
  }
}

}  // namespace
