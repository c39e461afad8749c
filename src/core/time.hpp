#pragma once
// Timestamps: int64 nanoseconds everywhere inside svslam (LCM utime is int64 microseconds).
#include <cstdint>

namespace svslam {

using TimeNs = std::int64_t;  // nanoseconds since an epoch stated by the producer

constexpr TimeNs kNsPerUs = 1000;
constexpr TimeNs kNsPerMs = 1000 * 1000;
constexpr TimeNs kNsPerS = 1000 * 1000 * 1000;

constexpr double nsToSeconds(TimeNs t_ns) { return static_cast<double>(t_ns) * 1e-9; }
constexpr TimeNs secondsToNs(double t_s) {
  return static_cast<TimeNs>(t_s * 1e9 + (t_s >= 0 ? 0.5 : -0.5));
}
constexpr std::int64_t nsToUtime(TimeNs t_ns) { return t_ns / kNsPerUs; }

}  // namespace svslam
