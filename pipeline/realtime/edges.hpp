#pragma once
// The edges between pipeline threads: bounded single-producer single-consumer hand-offs of
// pointers to pooled frame slots (nothing is copied, nothing allocated per frame).
//   BlockingEdge   a bounded lock-free SPSC ring (moodycamel::BlockingReaderWriterCircularBuffer):
//                  the producer waits when it is full (back-pressure, never drops); used between
//                  the processing stages and for replays as fast as possible.
//   NewestEdge     a one-place mailbox (lock-free exchange): the producer always replaces the
//                  waiting item with the newest, and the replaced one is handed back to the
//                  producer and counted as a drop; used after capture for cameras and real-time
//                  replays, where a late frame is worth less than the next one.
// Both: exactly one producer thread and one consumer thread; close() (by the producer) ends the
// stream after the items already queued. Counters are readable from any thread.
//   FeedbackCell   a value a later stage hands back to an earlier one about frame `seq` (the
//                  estimator's predicted motion for the stereo stage's ROIs); the reader waits
//                  for the frame it needs on the sequence number (C++20 atomic wait: a futex,
//                  no lock).
#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <readerwriterqueue/atomicops.h>
#include <readerwriterqueue/readerwritercircularbuffer.h>

namespace svslam::rt {

template <class T>
class BlockingEdge {
 public:
  explicit BlockingEdge(std::size_t capacity) : q_(capacity), capacity_(capacity) {}
  // Waits while the ring is full; returns the time waited (ns) for the stats.
  std::int64_t push(T* item) {
    const auto t0 = std::chrono::steady_clock::now();
    q_.wait_enqueue(item);
    noteDepth();
    return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() -
                                                                t0)
        .count();
  }
  // Next item, or nullptr once closed and drained. Waits at most `timeout` per call when the
  // ring is empty: returns false (and leaves `out`) on timeout so the caller can check for stop.
  bool pop(T*& out, std::chrono::microseconds timeout) {
    T* item = nullptr;
    if (!q_.wait_dequeue_timed(item, timeout.count())) return false;
    out = item;  // nullptr is the close marker
    return true;
  }
  void close() { q_.wait_enqueue(nullptr); }
  int depth() const { return static_cast<int>(q_.size_approx()); }
  int maxDepth() const { return max_depth_.load(std::memory_order_relaxed); }
  int capacity() const { return static_cast<int>(capacity_); }
  std::int64_t drops() const { return 0; }

 private:
  void noteDepth() {
    const int d = depth();
    int m = max_depth_.load(std::memory_order_relaxed);
    while (d > m && !max_depth_.compare_exchange_weak(m, d, std::memory_order_relaxed)) {
    }
  }
  moodycamel::BlockingReaderWriterCircularBuffer<T*> q_;
  std::size_t capacity_;
  std::atomic<int> max_depth_{0};
};

template <class T>
class NewestEdge {
 public:
  // Offers `item`; returns the item it replaced (a drop, to be recycled by the producer) or
  // nullptr.
  T* push(T* item) {
    T* old = slot_.exchange(item, std::memory_order_acq_rel);
    if (old) drops_.fetch_add(1, std::memory_order_relaxed);
    max_depth_.store(1, std::memory_order_relaxed);
    signal();
    return old;
  }
  // As BlockingEdge::pop: nullptr once closed and drained; false on timeout.
  bool pop(T*& out, std::chrono::microseconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    for (;;) {
      if (T* item = slot_.exchange(nullptr, std::memory_order_acq_rel)) {
        out = item;
        return true;
      }
      if (closed_.load(std::memory_order_acquire)) {
        out = slot_.exchange(nullptr, std::memory_order_acq_rel);  // nullptr: closed
        return true;
      }
      const auto left = std::chrono::duration_cast<std::chrono::microseconds>(
          deadline - std::chrono::steady_clock::now());
      if (left.count() <= 0) return false;
      // Every push and close signals once; extra counts only cause an extra loop turn.
      (void)sema_.wait(left.count());
    }
  }
  void close() {
    closed_.store(true, std::memory_order_release);
    sema_.signal();
  }
  int depth() const { return slot_.load(std::memory_order_relaxed) ? 1 : 0; }
  int maxDepth() const { return max_depth_.load(std::memory_order_relaxed); }
  int capacity() const { return 1; }
  std::int64_t drops() const { return drops_.load(std::memory_order_relaxed); }

 private:
  void signal() { sema_.signal(); }
  std::atomic<T*> slot_{nullptr};
  moodycamel::spsc_sema::LightweightSemaphore sema_;
  std::atomic<bool> closed_{false};
  std::atomic<std::int64_t> drops_{0};
  std::atomic<int> max_depth_{0};
};

// One writer thread publishes the value of frame `seq`, one reader thread waits for it. The
// reader asks for the frame it last handed downstream, and the writer cannot move past that
// frame until the reader sends the next one, so a value is never overwritten while read.
template <class T>
class FeedbackCell {
 public:
  void publish(std::int64_t seq, const T& value) {
    value_ = value;
    seq_.store(seq, std::memory_order_release);
    seq_.notify_all();
  }
  // Waits until the value of frame `seq` (or a later one) is there and copies it into `out`;
  // false when the cell was closed first.
  bool wait(std::int64_t seq, T& out) {
    for (;;) {
      const std::int64_t cur = seq_.load(std::memory_order_acquire);
      if (cur == kClosed) return false;
      if (cur >= seq) break;
      seq_.wait(cur, std::memory_order_acquire);
    }
    out = value_;
    return true;
  }
  // No value will come any more: every wait returns false.
  void close() {
    seq_.store(kClosed, std::memory_order_release);
    seq_.notify_all();
  }
  // Back to empty (between runs, no thread waiting).
  void reset() { seq_.store(-1, std::memory_order_relaxed); }

 private:
  static constexpr std::int64_t kClosed = std::numeric_limits<std::int64_t>::max();
  T value_{};
  std::atomic<std::int64_t> seq_{-1};
};

}  // namespace svslam::rt
