#pragma once
// Latency samples kept in preallocated storage (no allocation when a sample is added), with
// nearest-rank percentiles computed on demand (nth_element over a preallocated scratch copy).
// A recorder holds the last `capacity` samples; older ones are overwritten (count() keeps the
// total). Not thread-safe: one writer; read the summary after the writer has stopped or from the
// same thread.
#include <cstdint>
#include <string>
#include <vector>

namespace svslam::rt {

struct LatencySummary {
  std::int64_t count = 0;  // samples ever added
  double p50_ms = 0, p99_ms = 0, max_ms = 0, mean_ms = 0;  // over the samples kept
};

class LatencyRecorder {
 public:
  explicit LatencyRecorder(std::size_t capacity = 1 << 16);
  void add(std::int64_t ns);
  // Percentile p in [0, 100] (nearest rank) of the kept samples, ms; 0 when empty.
  double percentileMs(double p) const;
  LatencySummary summary() const;
  std::int64_t count() const { return count_; }
  void clear();

 private:
  std::vector<std::int64_t> samples_;
  mutable std::vector<std::int64_t> scratch_;
  std::size_t next_ = 0;
  std::int64_t count_ = 0;
  std::int64_t max_ns_ = 0;
};

// {"p50_ms": .., "p99_ms": .., "max_ms": .., "mean_ms": .., "count": n}
std::string latencyJson(const LatencySummary& s);

}  // namespace svslam::rt
