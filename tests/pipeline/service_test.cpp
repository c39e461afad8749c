// `svslam run` as a systemd service, without systemd: a unix datagram socket stands in for
// NOTIFY_SOCKET and receives READY=1 (after the first pose), WATCHDOG=1 (from the pipeline's
// health check while frames complete) and STOPPING=1; SIGTERM mid-run stops capture, drains,
// writes every output whole and exits 0; so does a stop signal during --preload, while an lcm:
// source waits for its first frame, at the very start, and SIGHUP.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <pthread.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "cli_helpers.hpp"
#include "sanitizer_time_scale.hpp"

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using svslam::test::slurp;

namespace {

int countOf(const std::string& s, const std::string& needle) {
  int n = 0;
  for (std::size_t p = s.find(needle); p != std::string::npos; p = s.find(needle, p + 1)) ++n;
  return n;
}

class Service : public ::testing::Test {
 public:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("svslam_svc_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    sock_path_ = (dir_ / "notify.sock").string();
    fd_ = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    ASSERT_GE(fd_, 0);
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    std::strncpy(addr.sun_path, sock_path_.c_str(), sizeof(addr.sun_path) - 1);
    ASSERT_EQ(::bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0);
    timeval tv{0, 100000};
    ::setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  }
  void TearDown() override {
    ::close(fd_);
    fs::remove_all(dir_);
  }
  // Starts svslam run with the notify environment; returns its pid. With block_stop_signals
  // it starts with SIGTERM, SIGINT and SIGHUP blocked (pending until svslam unblocks them),
  // executed directly (no shell, which would reset the mask; `args` then has no quotes).
  pid_t start(const std::string& args, bool block_stop_signals = false) {
    // Blocked before fork (the child inherits the mask): a signal sent right after start()
    // returns cannot hit the child before its mask is set.
    sigset_t set, old;
    sigemptyset(&set);
    for (int sig : {SIGTERM, SIGINT, SIGHUP}) sigaddset(&set, sig);
    if (block_stop_signals) ::pthread_sigmask(SIG_BLOCK, &set, &old);
    const pid_t pid = ::fork();
    if (pid != 0 && block_stop_signals) ::pthread_sigmask(SIG_SETMASK, &old, nullptr);
    if (pid == 0) {
      ::setenv("NOTIFY_SOCKET", sock_path_.c_str(), 1);
      ::setenv("WATCHDOG_USEC", "400000", 1);  // ping every 200 ms while frames complete
      ::setenv("WATCHDOG_PID", std::to_string(::getpid()).c_str(), 1);
      const std::string out = (dir_ / "stdout.txt").string(), err = (dir_ / "stderr.txt").string();
      if (block_stop_signals) {
        std::vector<std::string> words{SVSLAM_CLI, "run"};
        std::istringstream ss(args + " --out " + (dir_ / "out").string());
        for (std::string w; ss >> w;) words.push_back(w);
        std::vector<char*> argv;
        for (auto& w : words) argv.push_back(w.data());
        argv.push_back(nullptr);
        ::dup2(::open(out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644), 1);
        ::dup2(::open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644), 2);
        ::execv(SVSLAM_CLI, argv.data());
        ::_exit(127);
      }
      const std::string cmd = std::string("exec ") + SVSLAM_CLI + " run " + args + " --out " +
                              (dir_ / "out").string() + " > " + out + " 2> " + err;
      ::execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
      ::_exit(127);
    }
    return pid;
  }
  // Reads notifications until `until` is seen or the deadline passes; returns all of them.
  std::string readUntil(const std::string& until, std::chrono::seconds timeout) {
    const auto t0 = std::chrono::steady_clock::now();
    while (std::chrono::steady_clock::now() - t0 < timeout) {
      char buf[512];
      const ssize_t n = ::recv(fd_, buf, sizeof buf - 1, 0);
      if (n > 0) {
        buf[n] = 0;
        got_ += std::string(buf) + "\n";
        if (got_.find(until) != std::string::npos) break;
      }
    }
    return got_;
  }
  // Reads every notification already queued.
  void drain() {
    char buf[512];
    for (;;) {
      const ssize_t n = ::recv(fd_, buf, sizeof buf - 1, MSG_DONTWAIT);
      if (n <= 0) return;
      buf[n] = 0;
      got_ += std::string(buf) + "\n";
    }
  }
  fs::path dir_;
  std::string sock_path_;
  int fd_ = -1;
  std::string got_;
};

int waitExit(pid_t pid) {
  int st = 0;
  ::waitpid(pid, &st, 0);
  return svslam::test::exitCode(st);
}

// The exit code of `pid`, or -1 (after SIGKILL) when it has not ended within `timeout`.
int waitExitWithin(pid_t pid, std::chrono::seconds timeout) {
  const auto t0 = std::chrono::steady_clock::now();
  while (std::chrono::steady_clock::now() - t0 < timeout) {
    int st = 0;
    if (::waitpid(pid, &st, WNOHANG) == pid) return svslam::test::exitCode(st);
    std::this_thread::sleep_for(20ms);
  }
  ::kill(pid, SIGKILL);
  waitExit(pid);
  return -1;
}

// True once `file` contains `text` (polled up to `timeout`).
bool waitForText(const fs::path& file, const std::string& text, std::chrono::seconds timeout) {
  const auto t0 = std::chrono::steady_clock::now();
  while (std::chrono::steady_clock::now() - t0 < timeout) {
    if (slurp(file).find(text) != std::string::npos) return true;
    std::this_thread::sleep_for(20ms);
  }
  return false;
}

TEST_F(Service, ReadyWatchdogAndCleanStopOnSigterm) {
  // A long paced replay: SIGTERM arrives in the middle of it.
  const pid_t pid = start("--source synthetic:width=320,height=240,frames=2000 --rate 20");
  ASSERT_GT(pid, 0);
  const std::string ready = readUntil("READY=1", 60s);
  ASSERT_NE(ready.find("READY=1"), std::string::npos) << slurp(dir_ / "stderr.txt");
  readUntil("WATCHDOG=1", 10s);
  readUntil("\nWATCHDOG=1", 10s);  // a second ping: pings repeat while frames complete
  std::this_thread::sleep_for(500ms);
  ASSERT_EQ(::kill(pid, SIGTERM), 0);
  const std::string all = readUntil("STOPPING=1", 30s);
  const std::size_t at_stop = all.size();
  // Keep reading until the process is gone (as systemd does), so it never waits on the socket.
  int rc = -1;
  for (int i = 0; i < 600; ++i) {
    int st = 0;
    if (::waitpid(pid, &st, WNOHANG) == pid) {
      rc = svslam::test::exitCode(st);
      break;
    }
    drain();
    std::this_thread::sleep_for(100ms);
  }
  if (rc == -1) {
    ::kill(pid, SIGKILL);
    rc = waitExit(pid);
  }
  // No watchdog ping after STOPPING=1.
  EXPECT_EQ(got_.substr(at_stop).find("WATCHDOG=1"), std::string::npos) << got_.substr(at_stop);
  EXPECT_EQ(rc, 0) << slurp(dir_ / "stderr.txt");
  EXPECT_GE(countOf(all, "WATCHDOG=1"), 2) << all;
  EXPECT_NE(all.find("STOPPING=1"), std::string::npos) << all;
  // Every output whole: one line per frame in each file, stats.json complete, the map there.
  const fs::path out = dir_ / "out";
  const std::string traj = slurp(out / "trajectory_kitti.txt");
  const std::string cov = slurp(out / "pose_covariance.txt");
  const std::string stats = slurp(out / "stats.json");
  const int frames = countOf(traj, "\n");
  EXPECT_GT(frames, 0);
  EXPECT_LT(frames, 2000);
  EXPECT_EQ(countOf(cov, "\n"), frames);
  EXPECT_EQ(traj.back(), '\n');
  EXPECT_NE(stats.find("\"frames\": " + std::to_string(frames) + ","), std::string::npos) << stats;
  EXPECT_EQ(stats.back(), '\n');
  EXPECT_TRUE(fs::exists(out / "landmarks.ply"));
  // Without the fault hook no stage stalls.
  EXPECT_NE(stats.find(R"("stalls": {"timeout_s": 5.000, "count": 0, "stages": []})"),
            std::string::npos)
      << stats;
  EXPECT_EQ(got_.find("STATUS=stalled"), std::string::npos) << got_;
  for (const auto& e : fs::directory_iterator(out))  // no temporary file left behind
    EXPECT_EQ(e.path().string().find(".tmp"), std::string::npos) << e.path();
  EXPECT_NE(slurp(dir_ / "stderr.txt").find("stop requested (signal 15)"), std::string::npos);
}

// A notification and when it arrived (s since the start of the collection).
struct Note {
  double t_s;
  std::string text;
};

// Notifications until `pid` exits (at most `timeout`, then SIGKILL); returns the exit code.
int collectUntilExit(int fd, pid_t pid, std::vector<Note>& notes, std::chrono::seconds timeout) {
  const auto t0 = std::chrono::steady_clock::now();
  auto since = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  };
  for (;;) {
    char buf[512];
    const ssize_t n = ::recv(fd, buf, sizeof buf - 1, 0);  // SO_RCVTIMEO: 100 ms
    if (n > 0) {
      buf[n] = 0;
      notes.push_back({since(), buf});
      continue;
    }
    int st = 0;
    if (::waitpid(pid, &st, WNOHANG) == pid) return svslam::test::exitCode(st);
    if (since() > static_cast<double>(timeout.count())) {
      ::kill(pid, SIGKILL);
      waitExit(pid);
      return -1;
    }
  }
}

// The index of the first note at or after `from` containing `text` (-1: none).
int findNote(const std::vector<Note>& notes, const std::string& text, int from = 0) {
  for (int i = std::max(from, 0); i < static_cast<int>(notes.size()); ++i)
    if (notes[static_cast<std::size_t>(i)].text.find(text) != std::string::npos) return i;
  return -1;
}

// The number after `key` in `text` (NaN when absent).
double numberAfter(const std::string& text, const std::string& key) {
  const std::size_t at = text.find(key);
  return at == std::string::npos ? NAN : std::atof(text.c_str() + at + key.size());
}

// pipeline.fault's hook makes `stage` sleep stall_ms once, longer than service.stall_timeout_s:
// the health check names the stage in STATUS=, sends no WATCHDOG=1 from then until the stage
// recovers, pings again afterwards, and stats.json counts one stall of that stage (and nothing
// else). For the mapper (after publication) poses keep coming during the stall, so only the
// stage check stops the pings.
// `extra`: more configuration (the mapper, at nice +10, can take over a second for a frame on
// saturated cores: a run that does not test it leaves it out).
// timeout_s and stall_ms are for a release build; a sanitizer build scales both (its ordinary
// frames can take longer than the release timeout).
void expectStallReported(Service& t, int fd, const fs::path& dir, const std::string& stage,
                         double release_timeout_s, int release_stall_ms,
                         const std::string& extra) {
  const double timeout_s = release_timeout_s * svslam::test::kSanitizerTimeScale;
  const int stall_ms =
      static_cast<int>(release_stall_ms * svslam::test::kSanitizerTimeScale);
  const std::string cfg = (dir / "stall.yaml").string();
  std::ofstream(cfg) << "service: {stall_timeout_s: " << timeout_s << "}\n"
                     << extra << "pipeline:\n  fault: {stall_stage: " << stage
                     << ", stall_frame: 20, stall_ms: " << stall_ms << "}\n";
  const pid_t pid =
      t.start("--source synthetic:width=320,height=240,frames=100 --rate 20 --config " + cfg);
  ASSERT_GT(pid, 0);
  std::vector<Note> notes;
  const int rc = collectUntilExit(fd, pid, notes, 180s);
  const std::string err = slurp(dir / "stderr.txt");
  ASSERT_EQ(rc, 0) << err;
  std::string all;
  for (const Note& n : notes) all += std::to_string(n.t_s) + " " + n.text + "\n";
  // The stall episodes: a "stalled" note and the next recovery note of the stage. The injected
  // stall is the longest; a release build has exactly that one, a sanitizer build on loaded
  // cores may also have ordinary frames slower than its (scaled) timeout.
  const std::string stalled_text = "STATUS=stalled: stage " + stage + " working on one frame";
  int stalled = -1, recovered = -1, episodes = 0;
  for (int i = findNote(notes, stalled_text); i >= 0; i = findNote(notes, stalled_text, i + 1)) {
    const int r = findNote(notes, "STATUS=tracking; stage " + stage + " stalled ", i);
    if (r < 0) break;
    ++episodes;
    const auto gap = [&](int from, int to) {
      return notes[static_cast<std::size_t>(to)].t_s - notes[static_cast<std::size_t>(from)].t_s;
    };
    if (stalled < 0 || gap(i, r) > gap(stalled, recovered)) {
      stalled = i;
      recovered = r;
    }
    i = r;
  }
  ASSERT_GE(stalled, 0) << all << err;
  if (!svslam::test::kSanitized) {
    EXPECT_EQ(episodes, 1) << all;
  }
  const auto& ns = notes;
  // Reported once timeout_s passed, recovered when the sleep ends (the check runs every 100 ms).
  EXPECT_GE(ns[static_cast<std::size_t>(recovered)].t_s - ns[static_cast<std::size_t>(stalled)].t_s,
            stall_ms * 1e-3 - timeout_s - 0.5)
      << all;
  EXPECT_GE(findNote(notes, "WATCHDOG=1"), 0) << all;
  EXPECT_LT(findNote(notes, "WATCHDOG=1"), stalled) << all;  // pinging before the stall
  const int ping_in_stall = findNote(notes, "WATCHDOG=1", stalled);
  EXPECT_GT(ping_in_stall, recovered) << "a watchdog ping while '" << stage << "' was stalled\n"
                                      << all;
  EXPECT_GE(ping_in_stall, 0) << "no ping after the recovery\n" << all;
  EXPECT_NE(err.find("stage '" + stage + "' stalled: working on one frame"), std::string::npos)
      << err;
  EXPECT_NE(err.find("stage '" + stage + "' recovered"), std::string::npos) << err;
  const std::string stats = slurp(dir / "out" / "stats.json");
  char timeout[32];
  std::snprintf(timeout, sizeof timeout, "%.3f", timeout_s);
  const std::string header = std::string(R"("stalls": {"timeout_s": )") + timeout + R"(, "count": )";
  ASSERT_NE(stats.find(header), std::string::npos) << stats;
  const std::string entry = R"({"stage": ")" + stage + R"(", "count": )";
  ASSERT_NE(stats.find(entry), std::string::npos) << stats;
  const double stage_count = numberAfter(stats, entry);
  const std::string longest_key =
      entry + std::to_string(static_cast<int>(stage_count)) + R"(, "longest_ms": )";
  const double longest = numberAfter(stats, longest_key);
  if (!svslam::test::kSanitized) {  // that stall and nothing else
    EXPECT_EQ(numberAfter(stats, header), 1.0) << stats;
    EXPECT_EQ(stage_count, 1.0) << stats;
  } else {
    EXPECT_GE(stage_count, 1.0) << stats;
  }
  EXPECT_GE(longest, stall_ms) << stats;
  EXPECT_LT(longest, stall_ms + 20000.0) << stats;
}

TEST_F(Service, StalledEstimatorStopsThePingsAndIsNamed) {
  expectStallReported(*this, fd_, dir_, "estimator", 1.0, 2500, "map: {enabled: false}\n");
}

TEST_F(Service, StalledMapperStopsThePingsWhilePosesFlow) {
  expectStallReported(*this, fd_, dir_, "mapper", 1.5, 3000, "");
}

TEST_F(Service, StallHookOnAStageThisRunLacksIsRefused) {
  const std::string cfg = (dir_ / "nomap.yaml").string();
  std::ofstream(cfg) << "map: {enabled: false}\npipeline: {fault: {stall_stage: mapper}}\n";
  const int rc = waitExit(start("--source synthetic:width=320,height=240,frames=3 --config " + cfg));
  const std::string err = slurp(dir_ / "stderr.txt");
  EXPECT_EQ(rc, 1) << err;
  EXPECT_NE(err.find("pipeline.fault.stall_stage: stall fault: this pipeline has no stage "
                     "'mapper' (stages: capture, stereo, estimator, publisher)"),
            std::string::npos)
      << err;
}

TEST_F(Service, NoWatchdogPingWithoutProgress) {
  // A source that fails to open: the process exits non-zero and never says READY=1.
  const pid_t pid = start("--source kitti:/nonexistent/folder");
  const int rc = waitExit(pid);
  EXPECT_NE(rc, 0);
  const std::string all = readUntil("READY=1", 1s);
  EXPECT_EQ(all.find("READY=1"), std::string::npos) << all;
  EXPECT_EQ(all.find("WATCHDOG=1"), std::string::npos) << all;
  EXPECT_NE(slurp(dir_ / "stderr.txt").find("/nonexistent/folder"), std::string::npos);
}

// A stop signal at any moment of `svslam run` ends it in order: exit 0, stats.json written.
class StopSignal : public Service {
 protected:
  void SetUp() override {
    Service::SetUp();
    config_ = (dir_ / "c.yaml").string();
    std::ofstream(config_) << "dense_stereo: {enabled: false}\nmap: {enabled: false}\n";
  }
  // The run ended with exit 0 and whole outputs.
  void expectWholeOutputs(int rc) {
    const std::string err = slurp(dir_ / "stderr.txt");
    EXPECT_EQ(rc, 0) << err;
    const std::string stats = slurp(dir_ / "out" / "stats.json");
    EXPECT_NE(stats.find("\"frames\": "), std::string::npos) << stats << err;
    EXPECT_FALSE(stats.empty() || stats.back() != '\n') << stats;
    EXPECT_TRUE(fs::exists(dir_ / "out" / "trajectory_kitti.txt"));
    EXPECT_NE(slurp(dir_ / "stdout.txt").find("\"stopped_by_signal\": true"), std::string::npos)
        << slurp(dir_ / "stdout.txt");
  }
  std::string config_;
};

TEST_F(StopSignal, SigtermDuringPreload) {
  const pid_t pid =
      start("--source synthetic:width=320,height=240,frames=5000 --preload --config " + config_);
  ASSERT_TRUE(waitForText(dir_ / "stderr.txt", "reading the sequence into memory", 30s))
      << slurp(dir_ / "stderr.txt");
  std::this_thread::sleep_for(200ms);
  ASSERT_EQ(::kill(pid, SIGTERM), 0);
  expectWholeOutputs(waitExitWithin(pid, 60s));
}

TEST_F(StopSignal, SigtermWhileAnLcmSourceWaitsForItsFirstFrame) {
  // Stop signals blocked until svslam installs its handlers (a sanitizer build can take over a
  // second to get there); by then, or soon after, it waits for the first frame.
  const pid_t pid =
      start("--source lcm:NOBODY_SENDS?timeout_s=120&url=memq:// --config " + config_, true);
  std::this_thread::sleep_for(1s);
  ASSERT_EQ(::kill(pid, SIGTERM), 0);
  const int rc = waitExitWithin(pid, 20s);
  expectWholeOutputs(rc);
  EXPECT_NE(slurp(dir_ / "out" / "stats.json").find("\"frames\": 0,"), std::string::npos);
  EXPECT_NE(slurp(dir_ / "stderr.txt").find("stopped before the first frame"), std::string::npos)
      << slurp(dir_ / "stderr.txt");
}

TEST_F(StopSignal, SigtermAtTheVeryStart) {
  // Sent before svslam has even started: it is pending until the handlers are installed.
  const pid_t pid =
      start("--source synthetic:width=320,height=240,frames=30 --config " + config_, true);
  ASSERT_EQ(::kill(pid, SIGTERM), 0);
  expectWholeOutputs(waitExitWithin(pid, 60s));
  EXPECT_NE(slurp(dir_ / "stderr.txt").find("stop requested (signal 15)"), std::string::npos);
}

TEST_F(StopSignal, SighupMidRun) {
  const pid_t pid =
      start("--source synthetic:width=320,height=240,frames=2000 --rate 20 --config " + config_);
  ASSERT_NE(readUntil("READY=1", 60s).find("READY=1"), std::string::npos)
      << slurp(dir_ / "stderr.txt");
  ASSERT_EQ(::kill(pid, SIGHUP), 0);
  int rc = -1;
  for (int i = 0; i < 600 && rc == -1; ++i) {  // read the notifications as systemd would
    int st = 0;
    if (::waitpid(pid, &st, WNOHANG) == pid) rc = svslam::test::exitCode(st);
    drain();
    std::this_thread::sleep_for(100ms);
  }
  if (rc == -1) {
    ::kill(pid, SIGKILL);
    waitExit(pid);
  }
  expectWholeOutputs(rc);
  EXPECT_NE(slurp(dir_ / "stderr.txt").find("stop requested (signal 1)"), std::string::npos);
}

}  // namespace
