#include "pipeline/service/stop_signal.hpp"

#include <pthread.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdint>
#include <cstring>
#include <string>

namespace svslam::service {
namespace {

static_assert(std::atomic<int>::is_always_lock_free, "the signal handler needs lock-free atomics");

std::atomic<int> g_requested{0};     // 1 once a stop was requested
std::atomic<int> g_signal{0};        // first signal number that requested it, 0 = none
std::atomic<int> g_signal_count{0};  // stop signals received since the last reset
std::atomic<int> g_event_fd{-1};     // eventfd, -1 until created

void wakePollers() {
  const int fd = g_event_fd.load();
  if (fd < 0) return;
  const std::uint64_t one = 1;
  const int saved_errno = errno;  // the handler must not clobber errno of the interrupted code
  [[maybe_unused]] const ssize_t n = write(fd, &one, sizeof(one));
  errno = saved_errno;
}

void onStopSignal(int sig) {
  if (g_signal_count.fetch_add(1) > 0) {
    // Second signal: default action (terminate) for this signal, re-raised; it is delivered
    // when this handler returns and the signal is unblocked again.
    struct sigaction dfl;
    std::memset(&dfl, 0, sizeof(dfl));
    dfl.sa_handler = SIG_DFL;
    sigemptyset(&dfl.sa_mask);
    sigaction(sig, &dfl, nullptr);
    raise(sig);
    return;
  }
  int expected = 0;
  g_signal.compare_exchange_strong(expected, sig);
  g_requested.store(1);
  wakePollers();
}

int ensureEventFd() {
  // Function-local static: thread-safe one-time creation (never from the signal handler).
  static const int fd = [] {
    const int created = eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
    if (created >= 0) {
      g_event_fd.store(created);
      if (g_requested.load() != 0) wakePollers();  // a request that came before the fd existed
    }
    return created;
  }();
  return fd;
}

std::string errnoText(const char* what) {
  return std::string(what) + " failed: " + std::strerror(errno);
}

}  // namespace

Status installStopSignalHandlers() {
  if (ensureEventFd() < 0) return Status::ioError(errnoText("eventfd for the stop signal"));
  struct sigaction sa;
  std::memset(&sa, 0, sizeof(sa));
  sa.sa_handler = onStopSignal;
  sa.sa_flags = 0;  // no SA_RESTART: blocking calls in the receiving thread return EINTR
  sigemptyset(&sa.sa_mask);
  sigaddset(&sa.sa_mask, SIGTERM);  // the handlers never interleave
  sigaddset(&sa.sa_mask, SIGINT);
  sigaddset(&sa.sa_mask, SIGHUP);
  for (const int sig : {SIGTERM, SIGINT, SIGHUP}) {
    if (sigaction(sig, &sa, nullptr) != 0)
      return Status::ioError(errnoText(("sigaction(" + std::string(strsignal(sig)) + ")").c_str()));
  }
  if (pthread_sigmask(SIG_UNBLOCK, &sa.sa_mask, nullptr) != 0)
    return Status::ioError("pthread_sigmask failed: cannot unblock the stop signals");
  return Status::ok();
}

bool stopRequested() { return g_requested.load() != 0; }

int stopSignalNumber() { return g_signal.load(); }

void requestStop() {
  g_requested.store(1);
  wakePollers();
}

void resetStopRequest() {
  g_requested.store(0);
  g_signal.store(0);
  g_signal_count.store(0);
  const int fd = g_event_fd.load();
  if (fd >= 0) {
    std::uint64_t value = 0;
    [[maybe_unused]] const ssize_t n = read(fd, &value, sizeof(value));  // EAGAIN when empty
  }
}

int stopEventFd() { return ensureEventFd(); }

}  // namespace svslam::service
