#include "pipeline/realtime/latency_stats.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace svslam::rt {

LatencyRecorder::LatencyRecorder(std::size_t capacity)
    : samples_(std::max<std::size_t>(capacity, 1)), scratch_(samples_.size()) {}

void LatencyRecorder::add(std::int64_t ns) {
  samples_[next_] = ns;
  next_ = (next_ + 1) % samples_.size();
  ++count_;
  max_ns_ = count_ == 1 ? ns : std::max(max_ns_, ns);
}

void LatencyRecorder::clear() {
  next_ = 0;
  count_ = 0;
  max_ns_ = 0;
}

double LatencyRecorder::percentileMs(double p) const {
  const std::size_t n = static_cast<std::size_t>(
      std::min<std::int64_t>(count_, static_cast<std::int64_t>(samples_.size())));
  if (n == 0) return 0.0;
  std::copy(samples_.begin(), samples_.begin() + static_cast<std::ptrdiff_t>(n), scratch_.begin());
  // Nearest rank: the smallest sample with at least p % of the samples <= it.
  const double rank = std::ceil(std::clamp(p, 0.0, 100.0) / 100.0 * static_cast<double>(n));
  const std::size_t k = static_cast<std::size_t>(std::max(rank, 1.0)) - 1;
  std::nth_element(scratch_.begin(), scratch_.begin() + static_cast<std::ptrdiff_t>(k),
                   scratch_.begin() + static_cast<std::ptrdiff_t>(n));
  return static_cast<double>(scratch_[k]) * 1e-6;
}

LatencySummary LatencyRecorder::summary() const {
  LatencySummary s;
  s.count = count_;
  if (count_ == 0) return s;
  s.p50_ms = percentileMs(50);
  s.p99_ms = percentileMs(99);
  const std::size_t n = static_cast<std::size_t>(
      std::min<std::int64_t>(count_, static_cast<std::int64_t>(samples_.size())));
  double sum = 0;
  std::int64_t mx = 0;
  for (std::size_t i = 0; i < n; ++i) {
    sum += static_cast<double>(samples_[i]);
    mx = std::max(mx, samples_[i]);
  }
  s.mean_ms = sum / static_cast<double>(n) * 1e-6;
  s.max_ms = static_cast<double>(count_ > static_cast<std::int64_t>(samples_.size()) ? max_ns_ : mx) * 1e-6;
  return s;
}

std::string latencyJson(const LatencySummary& s) {
  char buf[256];
  std::snprintf(buf, sizeof buf,
                "{\"p50_ms\": %.3f, \"p99_ms\": %.3f, \"max_ms\": %.3f, \"mean_ms\": %.3f, "
                "\"count\": %lld}",
                s.p50_ms, s.p99_ms, s.max_ms, s.mean_ms, static_cast<long long>(s.count));
  return buf;
}

}  // namespace svslam::rt
