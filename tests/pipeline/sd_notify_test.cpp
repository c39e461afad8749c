// ServiceNotifier against a fake notify socket (an AF_UNIX datagram socket bound at a temp path,
// as systemd would provide), and the HealthWatchdog ping logic on a fake clock.
#include "pipeline/service/sd_notify.hpp"

#include <gtest/gtest.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string>

namespace svslam::service {
namespace {

constexpr std::int64_t kMs = 1'000'000;  // ns per ms

// Saves and restores the three variables the notifier reads.
class NotifyEnv {
 public:
  NotifyEnv() {
    for (int i = 0; i < 3; ++i) {
      const char* v = std::getenv(kNames[i]);
      had_[i] = v != nullptr;
      if (v) saved_[i] = v;
      unsetenv(kNames[i]);
    }
  }
  ~NotifyEnv() {
    for (int i = 0; i < 3; ++i) {
      if (had_[i]) {
        setenv(kNames[i], saved_[i].c_str(), 1);
      } else {
        unsetenv(kNames[i]);
      }
    }
  }

 private:
  static constexpr const char* kNames[3] = {"NOTIFY_SOCKET", "WATCHDOG_USEC", "WATCHDOG_PID"};
  bool had_[3] = {false, false, false};
  std::string saved_[3];
};

// A bound datagram socket standing in for systemd's notify socket.
class FakeNotifySocket {
 public:
  FakeNotifySocket() {
    char tmpl[] = "/tmp/svslam_notify_XXXXXX";
    const char* dir = mkdtemp(tmpl);
    if (dir == nullptr) return;
    dir_ = dir;
    path_ = dir_ + "/notify.sock";
    fd_ = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    std::strncpy(addr.sun_path, path_.c_str(), sizeof(addr.sun_path) - 1);
    if (fd_ >= 0 && bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) != 0) {
      close(fd_);
      fd_ = -1;
    }
  }
  ~FakeNotifySocket() {
    if (fd_ >= 0) close(fd_);
    if (!path_.empty()) unlink(path_.c_str());
    if (!dir_.empty()) rmdir(dir_.c_str());
  }
  bool ok() const { return fd_ >= 0; }
  const std::string& path() const { return path_; }

  // The next datagram, or "" when none arrives within timeout_ms.
  std::string receive(int timeout_ms = 1000) {
    pollfd p{fd_, POLLIN, 0};
    if (poll(&p, 1, timeout_ms) != 1) return "";
    char buf[4096];
    const ssize_t n = recv(fd_, buf, sizeof(buf), 0);
    return n > 0 ? std::string(buf, static_cast<std::size_t>(n)) : "";
  }

 private:
  std::string dir_;
  std::string path_;
  int fd_ = -1;
};

TEST(ServiceNotifier, SendsEachStateToTheNotifySocket) {
  NotifyEnv env;
  FakeNotifySocket sock;
  ASSERT_TRUE(sock.ok()) << "cannot bind a unix datagram socket under /tmp";
  setenv("NOTIFY_SOCKET", sock.path().c_str(), 1);
  setenv("WATCHDOG_USEC", "200000", 1);
  setenv("WATCHDOG_PID", std::to_string(getpid()).c_str(), 1);

  ServiceNotifier n;
  EXPECT_TRUE(n.enabled());
  EXPECT_EQ(n.watchdogIntervalNs(), 200 * kMs);

  n.ready("tracking");
  EXPECT_EQ(sock.receive(), "READY=1\nSTATUS=tracking");
  n.watchdog();
  EXPECT_EQ(sock.receive(), "WATCHDOG=1");
  n.status("frame 42, 30.0 fps");
  EXPECT_EQ(sock.receive(), "STATUS=frame 42, 30.0 fps");
  n.stopping();
  EXPECT_EQ(sock.receive(), "STOPPING=1");
  n.watchdogTrigger();
  EXPECT_EQ(sock.receive(), "WATCHDOG=trigger");
  EXPECT_TRUE(n.send("RELOADING=1"));
  EXPECT_EQ(sock.receive(), "RELOADING=1");

  // The environment is left in place for children (unset_environment = 0).
  EXPECT_STREQ(std::getenv("NOTIFY_SOCKET"), sock.path().c_str());
  EXPECT_STREQ(std::getenv("WATCHDOG_USEC"), "200000");
}

TEST(ServiceNotifier, WatchdogForAnotherPidIsIgnored) {
  NotifyEnv env;
  FakeNotifySocket sock;
  ASSERT_TRUE(sock.ok());
  setenv("NOTIFY_SOCKET", sock.path().c_str(), 1);
  setenv("WATCHDOG_USEC", "200000", 1);
  setenv("WATCHDOG_PID", std::to_string(getpid() + 1).c_str(), 1);

  ServiceNotifier n;
  EXPECT_TRUE(n.enabled());
  EXPECT_EQ(n.watchdogIntervalNs(), 0);
  n.watchdog();  // no watchdog for us: nothing sent
  n.stopping();
  EXPECT_EQ(sock.receive(), "STOPPING=1");
}

TEST(ServiceNotifier, NoWatchdogWithoutWatchdogUsec) {
  NotifyEnv env;
  FakeNotifySocket sock;
  ASSERT_TRUE(sock.ok());
  setenv("NOTIFY_SOCKET", sock.path().c_str(), 1);

  ServiceNotifier n;
  EXPECT_TRUE(n.enabled());
  EXPECT_EQ(n.watchdogIntervalNs(), 0);
  n.watchdog();
  n.watchdogTrigger();
  EXPECT_EQ(sock.receive(100), "");
}

TEST(ServiceNotifier, EverythingIsANoOpWithoutNotifySocket) {
  NotifyEnv env;
  setenv("WATCHDOG_USEC", "200000", 1);  // a watchdog without a socket still sends nothing

  ServiceNotifier n;
  EXPECT_FALSE(n.enabled());
  n.ready("tracking");
  n.watchdog();
  n.status("x");
  n.stopping();
  n.watchdogTrigger();
  EXPECT_FALSE(n.send("READY=1"));
}

TEST(HealthWatchdog, PingsAtHalfIntervalWhileProgressing) {
  HealthWatchdog w(200 * kMs, 100 * kMs);
  EXPECT_FALSE(w.shouldPing(0)) << "no ping before the first progress";
  int pings = 0;
  // A frame every 10 ms for 1 s, the health check every 5 ms.
  for (std::int64_t t = 0; t <= 1000 * kMs; t += 5 * kMs) {
    if (t % (10 * kMs) == 0) w.progress(t);
    if (w.shouldPing(t)) ++pings;
  }
  // Pings at 0, 100, ..., 1000 ms.
  EXPECT_EQ(pings, 11);
}

TEST(HealthWatchdog, StopsPingingAfterAStallAndResumesAfterProgress) {
  HealthWatchdog w(200 * kMs, 100 * kMs);
  w.progress(0);
  EXPECT_TRUE(w.shouldPing(0));
  EXPECT_FALSE(w.shouldPing(50 * kMs)) << "less than interval/2 since the last ping";
  EXPECT_TRUE(w.shouldPing(100 * kMs)) << "100 ms since progress is not yet a stall";
  EXPECT_FALSE(w.stalled(100 * kMs));
  // No progress: 150 ms since the last frame is a stall; no ping however long we wait.
  EXPECT_TRUE(w.stalled(150 * kMs));
  for (std::int64_t t = 150 * kMs; t <= 2000 * kMs; t += 10 * kMs) {
    EXPECT_FALSE(w.shouldPing(t)) << "t = " << t / kMs << " ms";
  }
  // A frame completes again: pinging resumes at once (the last ping is long ago).
  w.progress(2005 * kMs);
  EXPECT_FALSE(w.stalled(2005 * kMs));
  EXPECT_TRUE(w.shouldPing(2005 * kMs));
  EXPECT_FALSE(w.shouldPing(2010 * kMs));
}

TEST(HealthWatchdog, IdleCountsAsProgress) {
  HealthWatchdog w(200 * kMs, 100 * kMs);
  w.progress(0);
  EXPECT_TRUE(w.shouldPing(0));
  int pings = 0;
  for (std::int64_t t = 10 * kMs; t <= 1000 * kMs; t += 10 * kMs) {
    w.idle(t);  // paused, but the health check sees it alive
    if (w.shouldPing(t)) ++pings;
  }
  EXPECT_EQ(pings, 10);
}

TEST(HealthWatchdog, DisabledWithoutInterval) {
  HealthWatchdog w(0, 100 * kMs);
  w.progress(0);
  EXPECT_FALSE(w.shouldPing(0));
  EXPECT_FALSE(w.shouldPing(1000 * kMs));
}

TEST(HealthWatchdog, OutOfOrderProgressDoesNotMoveBackwards) {
  HealthWatchdog w(200 * kMs, 100 * kMs);
  w.progress(500 * kMs);
  w.progress(100 * kMs);  // a late report from another stage
  EXPECT_FALSE(w.stalled(550 * kMs));
  EXPECT_TRUE(w.shouldPing(550 * kMs));
}

}  // namespace
}  // namespace svslam::service
