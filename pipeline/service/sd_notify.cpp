#include "pipeline/service/sd_notify.hpp"

#include <systemd/sd-daemon.h>

#include <algorithm>
#include <cstdlib>

namespace svslam::service {

ServiceNotifier::ServiceNotifier() {
  const char* socket = std::getenv("NOTIFY_SOCKET");
  enabled_ = socket != nullptr && socket[0] != '\0';
  std::uint64_t usec = 0;
  // > 0: WATCHDOG_USEC is set, valid, and WATCHDOG_PID (if set) is this process.
  if (sd_watchdog_enabled(/*unset_environment=*/0, &usec) > 0 && usec > 0) {
    watchdog_interval_ns_ = static_cast<std::int64_t>(usec) * 1000;
  }
}

bool ServiceNotifier::send(const std::string& state) const {
  if (!enabled_) return false;
  return sd_notify(/*unset_environment=*/0, state.c_str()) > 0;
}

void ServiceNotifier::ready(const std::string& status_text) {
  send("READY=1\nSTATUS=" + status_text);
}

void ServiceNotifier::watchdog() {
  if (watchdog_interval_ns_ > 0) send("WATCHDOG=1");
}

void ServiceNotifier::status(const std::string& text) { send("STATUS=" + text); }

void ServiceNotifier::stopping() { send("STOPPING=1"); }

void ServiceNotifier::watchdogTrigger() {
  if (watchdog_interval_ns_ > 0) send("WATCHDOG=trigger");
}

HealthWatchdog::HealthWatchdog(std::int64_t interval_ns, std::int64_t stall_ns)
    : interval_ns_(interval_ns), stall_ns_(std::max<std::int64_t>(stall_ns, 0)) {}

void HealthWatchdog::progress(std::int64_t now_ns) {
  if (!seen_progress_ || now_ns > last_progress_ns_) last_progress_ns_ = now_ns;
  seen_progress_ = true;
}

bool HealthWatchdog::stalled(std::int64_t now_ns) const {
  return seen_progress_ && now_ns - last_progress_ns_ > stall_ns_;
}

bool HealthWatchdog::shouldPing(std::int64_t now_ns) {
  if (interval_ns_ <= 0 || !seen_progress_) return false;
  if (now_ns - last_progress_ns_ > stall_ns_) return false;  // stuck: let systemd restart us
  if (pinged_ && now_ns - last_ping_ns_ < interval_ns_ / 2) return false;
  pinged_ = true;
  last_ping_ns_ = now_ns;
  return true;
}

}  // namespace svslam::service
