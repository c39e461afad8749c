#include "pipeline/realtime/stage_health.hpp"

#include <algorithm>
#include <chrono>
#include <utility>

namespace svslam::rt {
namespace {

std::int64_t nowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

// The stage this thread works for (StageWork), for StageWait.
thread_local StageHealth* t_health = nullptr;
thread_local std::size_t t_index = 0;

}  // namespace

std::int64_t HealthSnapshot::totalStalls() const {
  std::int64_t n = 0;
  for (const StageStall& s : stalls) n += s.count;
  return n;
}

StageHealth::StageHealth(std::vector<std::string> names)
    : names_(std::move(names)), entries_(std::make_unique<Entry[]>(names_.size())) {}

void StageHealth::reset() {
  for (std::size_t i = 0; i < names_.size(); ++i) {
    entries_[i].since_ns = 0;
    entries_[i].stalls = 0;
    entries_[i].longest_ns = 0;
  }
}

void StageHealth::begin(std::size_t index, std::int64_t now_ns) {
  entries_[index].since_ns.store(std::max<std::int64_t>(now_ns, 1));
}

void StageHealth::end(std::size_t index, std::int64_t now_ns) {
  Entry& e = entries_[index];
  const std::int64_t since = e.since_ns.load();
  if (since == 0) return;
  const std::int64_t d = now_ns - since;
  // Counted before the stretch is cleared: a reader that sees the same since_ns before and
  // after reading the counts saw them without this stretch (snapshot()).
  if (threshold_ns_ > 0 && d > threshold_ns_) {
    if (d > e.longest_ns.load()) e.longest_ns.store(d);
    e.stalls.fetch_add(1);
  }
  e.since_ns.store(0);
}

HealthSnapshot StageHealth::snapshot(std::int64_t now_ns) const {
  HealthSnapshot h;
  std::int64_t worst_ns = 0;
  for (std::size_t i = 0; i < names_.size(); ++i) {
    const Entry& e = entries_[i];
    std::int64_t since = 0, stalls = 0, longest = 0;
    for (int attempt = 0; attempt < 100; ++attempt) {  // a consistent read of the entry
      since = e.since_ns.load();
      stalls = e.stalls.load();
      longest = e.longest_ns.load();
      if (e.since_ns.load() == since) break;
    }
    const std::int64_t ongoing = since != 0 ? now_ns - since : 0;
    if (threshold_ns_ > 0 && ongoing > threshold_ns_) {
      ++stalls;
      longest = std::max(longest, ongoing);
      if (ongoing > worst_ns) {
        worst_ns = ongoing;
        h.stalled_stage = names_[i];
        h.stalled_ms = static_cast<double>(ongoing) * 1e-6;
      }
    }
    if (stalls > 0) h.stalls.push_back({names_[i], stalls, static_cast<double>(longest) * 1e-6});
  }
  return h;
}

StageWork::StageWork(StageHealth& health, std::size_t index) {
  t_health = &health;
  t_index = index;
  health.begin(index, nowNs());
}

StageWork::~StageWork() {
  t_health->end(t_index, nowNs());
  t_health = nullptr;
}

StageWait::StageWait() {
  if (t_health) t_health->end(t_index, nowNs());
}

StageWait::~StageWait() {
  if (t_health) t_health->begin(t_index, nowNs());
}

}  // namespace svslam::rt
