// Thread affinity / SCHED_FIFO with graceful degradation, thread names, and the stop-signal
// handling (StopSignal suite). Every scheduling change is made on a fresh std::thread so the
// test runner's own thread keeps its affinity and policy.
#include <gtest/gtest.h>
#include <poll.h>
#include <pthread.h>
#include <sched.h>
#include <sys/resource.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <string>
#include <thread>

#include "pipeline/service/scheduling.hpp"
#include "pipeline/service/stop_signal.hpp"

namespace svslam::service {
namespace {

void runOnNewThread(const std::function<void()>& fn) {
  std::thread t(fn);
  t.join();
}

TEST(ThreadScheduling, ValidateChecksRanges) {
  EXPECT_TRUE(ThreadScheduling{}.validate());
  EXPECT_TRUE((ThreadScheduling{{0, 1}, 99}).validate());
  const Status neg = ThreadScheduling{{-1}, 0}.validate();
  EXPECT_FALSE(neg);
  EXPECT_NE(neg.message().find("CPU -1"), std::string::npos) << neg.message();
  EXPECT_FALSE((ThreadScheduling{{0, 0}, 0}).validate()) << "a CPU listed twice";
  EXPECT_FALSE((ThreadScheduling{{}, 100}).validate());
  EXPECT_FALSE((ThreadScheduling{{}, -1}).validate());
}

TEST(ThreadScheduling, PinsToCpu0) {
  runOnNewThread([] {
    std::string warning = "stale";
    const Status s = applyToCurrentThread(ThreadScheduling{{0}, 0}, warning);
    ASSERT_TRUE(s) << s.message();
    EXPECT_TRUE(warning.empty()) << warning;
    cpu_set_t set;
    CPU_ZERO(&set);
    ASSERT_EQ(pthread_getaffinity_np(pthread_self(), sizeof(set), &set), 0);
    EXPECT_EQ(CPU_COUNT(&set), 1);
    EXPECT_TRUE(CPU_ISSET(0, &set));
  });
}

TEST(ThreadScheduling, CpuBeyondTheMachineIsAnErrorNamingIt) {
  const long configured = sysconf(_SC_NPROCESSORS_CONF);
  ASSERT_GT(configured, 0);
  const int missing = static_cast<int>(configured);
  runOnNewThread([missing] {
    cpu_set_t before;
    ASSERT_EQ(pthread_getaffinity_np(pthread_self(), sizeof(before), &before), 0);
    std::string warning;
    const Status s = applyToCurrentThread(ThreadScheduling{{0, missing}, 0}, warning);
    EXPECT_FALSE(s);
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
    EXPECT_NE(s.message().find("CPU " + std::to_string(missing)), std::string::npos)
        << s.message();
    cpu_set_t after;
    ASSERT_EQ(pthread_getaffinity_np(pthread_self(), sizeof(after), &after), 0);
    EXPECT_TRUE(CPU_EQUAL(&before, &after)) << "a failed request changes nothing";
  });
}

// Either outcome is legitimate depending on privileges (CAP_SYS_NICE, RLIMIT_RTPRIO, RT group
// budget); the result must be consistent with the warning.
TEST(ThreadScheduling, FifoAppliesOrDegradesWithAWarning) {
  runOnNewThread([] {
    std::string warning;
    const Status s = applyToCurrentThread(ThreadScheduling{{}, 10}, warning);
    ASSERT_TRUE(s) << s.message();
    int policy = -1;
    sched_param param{};
    ASSERT_EQ(pthread_getschedparam(pthread_self(), &policy, &param), 0);
    if (warning.empty()) {
      std::printf("SCHED_FIFO permitted here: applied\n");
      EXPECT_EQ(policy, SCHED_FIFO);
      EXPECT_EQ(param.sched_priority, 10);
      // fifo_priority 0 takes the thread back to normal scheduling.
      ASSERT_TRUE(applyToCurrentThread(ThreadScheduling{}, warning));
      EXPECT_TRUE(warning.empty());
      ASSERT_EQ(pthread_getschedparam(pthread_self(), &policy, &param), 0);
      EXPECT_EQ(policy, SCHED_OTHER);
    } else {
      std::printf("SCHED_FIFO not permitted here: %s\n", warning.c_str());
      EXPECT_NE(policy, SCHED_FIFO);
      EXPECT_EQ(warning.rfind("SCHED_FIFO priority 10 not permitted (EPERM): running with normal "
                              "scheduling; ",
                              0),
                0u)
          << warning;
    }
  });
}

// The degraded path, forced in a child process: no RLIMIT_RTPRIO and (when the test runs as
// root) an unprivileged uid, so SCHED_FIFO is refused with EPERM.
// Child process body: drop the right to real-time scheduling, ask for SCHED_FIFO 10, print the
// warning to stderr and exit 0 when the thread kept normal scheduling and the status is OK.
[[noreturn]] void requestFifoWithoutPrivilege() {
  rlimit none{};
  none.rlim_cur = 0;
  none.rlim_max = 0;
  if (setrlimit(RLIMIT_RTPRIO, &none) != 0) std::_Exit(4);
  if (geteuid() == 0 && (setgid(65534) != 0 || setuid(65534) != 0)) std::_Exit(5);
  std::string warning;
  const Status s = applyToCurrentThread(ThreadScheduling{{}, 10}, warning);
  int policy = -1;
  sched_param param{};
  pthread_getschedparam(pthread_self(), &policy, &param);
  std::fprintf(stderr, "%s\n", warning.c_str());
  std::_Exit(s && policy == SCHED_OTHER ? 0 : 1);
}

// The degraded path, forced in a child process: no RLIMIT_RTPRIO and (when the test runs as
// root) an unprivileged uid, so SCHED_FIFO is refused with EPERM.
TEST(ThreadScheduling, FifoRefusedDegradesToNormalSchedulingWithAWarning) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(requestFifoWithoutPrivilege(), ::testing::ExitedWithCode(0),
              "SCHED_FIFO priority 10 not permitted \\(EPERM\\): running with normal "
              "scheduling; grant CAP_SYS_NICE or LimitRTPRIO= in the unit");
}

TEST(ThreadScheduling, InvalidRequestIsRejectedBeforeAnythingApplies) {
  std::string warning;
  const Status s = applyToCurrentThread(ThreadScheduling{{0}, 100}, warning);
  EXPECT_FALSE(s);
  EXPECT_NE(s.message().find("fifo_priority 100"), std::string::npos) << s.message();
}

TEST(ThreadScheduling, ThreadNameIsTruncatedTo15Bytes) {
  runOnNewThread([] {
    setCurrentThreadName("svslam-stereo-matcher-stage");
    char name[32] = {};
    ASSERT_EQ(pthread_getname_np(pthread_self(), name, sizeof(name)), 0);
    EXPECT_STREQ(name, "svslam-stereo-m");
    setCurrentThreadName("capture");
    ASSERT_EQ(pthread_getname_np(pthread_self(), name, sizeof(name)), 0);
    EXPECT_STREQ(name, "capture");
  });
}

bool readable(int fd, int timeout_ms = 0) {
  pollfd p{fd, POLLIN, 0};
  return poll(&p, 1, timeout_ms) == 1 && (p.revents & POLLIN) != 0;
}

class StopSignal : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(installStopSignalHandlers());
    resetStopRequest();
  }
  void TearDown() override { resetStopRequest(); }
};

TEST_F(StopSignal, SigtermRequestsAStopWithoutKilling) {
  ASSERT_GE(stopEventFd(), 0);
  EXPECT_FALSE(stopRequested());
  EXPECT_FALSE(readable(stopEventFd()));
  ASSERT_EQ(raise(SIGTERM), 0);  // delivered before raise returns (single-threaded here)
  EXPECT_TRUE(stopRequested());
  EXPECT_EQ(stopSignalNumber(), SIGTERM);
  EXPECT_TRUE(readable(stopEventFd()));
  EXPECT_TRUE(readable(stopEventFd())) << "stays readable for every poller";
  resetStopRequest();
  EXPECT_FALSE(stopRequested());
  EXPECT_EQ(stopSignalNumber(), 0);
  EXPECT_FALSE(readable(stopEventFd()));
}

TEST_F(StopSignal, SigintIsHandledToo) {
  ASSERT_EQ(raise(SIGINT), 0);
  EXPECT_TRUE(stopRequested());
  EXPECT_EQ(stopSignalNumber(), SIGINT);
}

TEST_F(StopSignal, SighupIsHandledToo) {
  ASSERT_EQ(raise(SIGHUP), 0);
  EXPECT_TRUE(stopRequested());
  EXPECT_EQ(stopSignalNumber(), SIGHUP);
}

TEST_F(StopSignal, ASignalPendingWhileBlockedIsHandledAtInstall) {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGTERM);
  ASSERT_EQ(pthread_sigmask(SIG_BLOCK, &set, nullptr), 0);
  ASSERT_EQ(raise(SIGTERM), 0);  // pending (e.g. sent before svslam run got going)
  EXPECT_FALSE(stopRequested());
  ASSERT_TRUE(installStopSignalHandlers());  // unblocks: handled now
  EXPECT_TRUE(stopRequested());
  EXPECT_EQ(stopSignalNumber(), SIGTERM);
}

TEST_F(StopSignal, HandlersDoNotRestartSystemCalls) {
  for (const int sig : {SIGTERM, SIGINT, SIGHUP}) {
    struct sigaction sa {};
    ASSERT_EQ(sigaction(sig, nullptr, &sa), 0);
    EXPECT_EQ(sa.sa_flags & SA_RESTART, 0) << "signal " << sig;
    EXPECT_NE(sa.sa_handler, SIG_DFL);
    EXPECT_NE(sa.sa_handler, SIG_IGN);
  }
}

TEST_F(StopSignal, RequestStopWakesAThreadBlockedInPoll) {
  bool woke = false;
  std::thread waiter([&woke] { woke = readable(stopEventFd(), 10'000); });
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  requestStop();
  waiter.join();
  EXPECT_TRUE(woke);
  EXPECT_TRUE(stopRequested());
  EXPECT_EQ(stopSignalNumber(), 0) << "a programmatic stop carries no signal";
}

TEST_F(StopSignal, ResetAllowsANewRequest) {
  requestStop();
  resetStopRequest();
  EXPECT_FALSE(stopRequested());
  ASSERT_EQ(raise(SIGTERM), 0);
  EXPECT_TRUE(stopRequested());
  EXPECT_EQ(stopSignalNumber(), SIGTERM);
}

TEST_F(StopSignal, SecondSignalKills) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(
      {
        resetStopRequest();
        if (!installStopSignalHandlers()) std::_Exit(2);
        raise(SIGINT);
        if (!stopRequested()) std::_Exit(3);
        raise(SIGINT);  // default action: terminated by SIGINT
        std::_Exit(0);
      },
      ::testing::KilledBySignal(SIGINT), "");
  EXPECT_EXIT(
      {
        resetStopRequest();
        if (!installStopSignalHandlers()) std::_Exit(2);
        raise(SIGINT);
        raise(SIGTERM);  // either signal counts as the second one
        std::_Exit(0);
      },
      ::testing::KilledBySignal(SIGTERM), "");
}

}  // namespace
}  // namespace svslam::service
