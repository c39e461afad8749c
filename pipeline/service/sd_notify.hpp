#pragma once
// Service life cycle towards systemd: readiness, status text, stopping and the watchdog.
//
// ServiceNotifier is a thin wrapper over libsystemd's sd_notify(3) and sd_watchdog_enabled(3).
// It reads the environment once, in the constructor:
//   NOTIFY_SOCKET   set by systemd for Type=notify units: the datagram socket to notify on;
//   WATCHDOG_USEC   set when the unit has WatchdogSec=: the watchdog timeout in microseconds;
//   WATCHDOG_PID    the pid the watchdog is meant for (ignored when it is not this process).
// The environment is left untouched (unset_environment = 0) so child processes and tests see the
// same values. Outside systemd (no NOTIFY_SOCKET) every call is a no-op and enabled() is false.
//
// Life cycle used by `svslam run` (docs/service.md):
//   ready("tracking")      once the first pose is out        -> READY=1, STATUS=tracking
//   watchdog()             whenever HealthWatchdog::shouldPing() says so   -> WATCHDOG=1
//   status("...")          occasional human-readable state   -> STATUS=...
//   stopping()             on SIGTERM, before draining       -> STOPPING=1
//   watchdogTrigger()      a health check found the pipeline stuck -> WATCHDOG=trigger
//                          (systemd treats it as a missed watchdog: SIGABRT, then Restart=)
//
// Every member is safe to call from any thread: the object only holds values read at
// construction, and sd_notify opens a fresh socket per call. Copyable.
//
// HealthWatchdog decides *when* to send WATCHDOG=1. The ping is tied to pipeline progress,
// never to a bare timer: a pipeline that stops completing frames stops pinging, and systemd
// restarts it after WatchdogSec. It holds no thread and no clock; the caller passes now_ns from
// a monotonic clock (CLOCK_MONOTONIC, nanoseconds).
#include <cstdint>
#include <string>

namespace svslam::service {

class ServiceNotifier {
 public:
  // Reads NOTIFY_SOCKET / WATCHDOG_USEC / WATCHDOG_PID once. Never fails: a malformed
  // WATCHDOG_USEC is treated as "no watchdog".
  ServiceNotifier();

  // True when running under a notify socket (NOTIFY_SOCKET set and non-empty).
  bool enabled() const { return enabled_; }

  // The watchdog timeout in nanoseconds (WATCHDOG_USEC * 1000); 0 when no watchdog is requested
  // or WATCHDOG_PID names another process. Ping at half of it (HealthWatchdog does).
  std::int64_t watchdogIntervalNs() const { return watchdog_interval_ns_; }

  // READY=1 and STATUS=<status_text> in one datagram.
  void ready(const std::string& status_text);
  // WATCHDOG=1 (only when a watchdog is configured).
  void watchdog();
  // STATUS=<text>: free-form text shown by `systemctl status`.
  void status(const std::string& text);
  // STOPPING=1: the service began its orderly shutdown.
  void stopping();
  // WATCHDOG=trigger: ask systemd to act as if the watchdog had expired (only with a watchdog).
  void watchdogTrigger();

  // Sends one raw state string (several KEY=VALUE lines), e.g. "RELOADING=1". Returns false
  // when not enabled or when sending failed (the error is ignored: notifications are advisory).
  bool send(const std::string& state) const;

 private:
  bool enabled_ = false;
  std::int64_t watchdog_interval_ns_ = 0;
};

// Progress-gated watchdog pings. With interval_ns = the systemd watchdog timeout (ns) and
// stall_ns = how long without a completed frame counts as stuck (ns):
//   shouldPing(now) == true  iff  now - last_ping >= interval_ns / 2
//                             and  now - last_progress <= stall_ns
// and a true answer records now as the last ping. The first call pings immediately when progress
// has been seen. interval_ns <= 0 disables pinging (shouldPing is always false).
// After the last progress at t0, pings continue until t0 + stall_ns at most, so systemd restarts
// the process by t0 + stall_ns + interval_ns: choose stall_ns between interval_ns / 2 and
// interval_ns (with interval_ns / 2 the restart comes within 1.5 * interval_ns of the stall),
// and above the longest legitimate frame time.
// progress(t) is called when a frame completes; idle(t) when the pipeline is legitimately idle
// (paused, waiting for a camera reconnect within its timeout): both count as "alive".
// Times are monotonic nanoseconds; out-of-order times are clamped (never move backwards).
class HealthWatchdog {
 public:
  HealthWatchdog(std::int64_t interval_ns, std::int64_t stall_ns);

  void progress(std::int64_t now_ns);
  void idle(std::int64_t now_ns) { progress(now_ns); }
  bool shouldPing(std::int64_t now_ns);

  // True when progress has been seen and none within stall_ns of now_ns.
  bool stalled(std::int64_t now_ns) const;

  std::int64_t intervalNs() const { return interval_ns_; }
  std::int64_t stallNs() const { return stall_ns_; }

 private:
  std::int64_t interval_ns_;
  std::int64_t stall_ns_;
  bool seen_progress_ = false;
  std::int64_t last_progress_ns_ = 0;
  bool pinged_ = false;
  std::int64_t last_ping_ns_ = 0;
};

}  // namespace svslam::service
