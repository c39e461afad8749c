#pragma once
// The altimeter's readings (svslam_lcm.altitude_t on lcm.altitude_channel) between the thread
// that handles LCM and the estimator thread: the monocular mode's scale source
// (slam.mono_scale = altitude). A frame uses the latest reading taken at or before its capture
// time (the same readings give the same frames the same altitude, however late the estimator
// runs); the last kCapacity readings are kept.
#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <mutex>

#include "core/time.hpp"

namespace svslam::rt {

class AltitudeInbox {
 public:
  static constexpr std::size_t kCapacity = 256;

  // Any thread. A reading older than every one kept replaces the oldest (kept when not full).
  void push(TimeNs t_ns, double altitude_m) {
    std::lock_guard<std::mutex> lock(mu_);
    ring_[head_] = {t_ns, altitude_m};
    head_ = (head_ + 1) % kCapacity;
    if (size_ < kCapacity) ++size_;
    accepted_.fetch_add(1, std::memory_order_relaxed);
  }
  // Any thread: a message that was not a valid reading.
  void reject() { rejected_.fetch_add(1, std::memory_order_relaxed); }

  // The reading with the largest time <= t_ns (ties: the one received last); false when none.
  bool latestAtOrBefore(TimeNs t_ns, double& altitude_m) const {
    std::lock_guard<std::mutex> lock(mu_);
    bool found = false;
    TimeNs best = 0;
    for (std::size_t k = 0; k < size_; ++k) {
      const Reading& r = ring_[(head_ + kCapacity - size_ + k) % kCapacity];  // oldest first
      if (r.t_ns <= t_ns && (!found || r.t_ns >= best)) {
        best = r.t_ns;
        altitude_m = r.altitude_m;
        found = true;
      }
    }
    return found;
  }

  std::int64_t accepted() const { return accepted_.load(std::memory_order_relaxed); }
  std::int64_t rejected() const { return rejected_.load(std::memory_order_relaxed); }

 private:
  struct Reading {
    TimeNs t_ns = 0;
    double altitude_m = 0;
  };
  mutable std::mutex mu_;
  std::array<Reading, kCapacity> ring_{};
  std::size_t head_ = 0, size_ = 0;
  std::atomic<std::int64_t> accepted_{0}, rejected_{0};
};

}  // namespace svslam::rt
