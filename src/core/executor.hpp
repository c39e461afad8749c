#pragma once
// Executor: how a pure library stage runs independent tasks (row stripes) in parallel without
// owning threads. The stage decides the tasks; the caller injects the executor. Results must
// not depend on which executor or how many tasks are used.
#include <memory>
#include <type_traits>

namespace svslam {

// A non-owning reference to a callable `void(int task)`: what parallelFor runs. Unlike a
// std::function it never allocates, whatever the lambda captures; the callable must outlive
// the reference, which parallelFor's blocking contract guarantees for a temporary argument.
class TaskRef {
 public:
  template <class F, class = std::enable_if_t<!std::is_same_v<std::decay_t<F>, TaskRef> &&
                                              std::is_invocable_v<F&, int>>>
  TaskRef(F&& fn) noexcept  // NOLINT: implicit by design, like std::function
      : obj_(const_cast<void*>(static_cast<const void*>(std::addressof(fn)))),
        call_([](void* obj, int task) {
          (*static_cast<std::remove_reference_t<F>*>(obj))(task);
        }) {}
  void operator()(int task) const { call_(obj_, task); }

 private:
  void* obj_;
  void (*call_)(void*, int);
};

class Executor {
 public:
  virtual ~Executor() = default;
  // Runs fn(0) .. fn(num_tasks - 1), possibly concurrently, and returns when all are done.
  virtual void parallelFor(int num_tasks, TaskRef fn) = 0;
  // How many tasks can usefully run at once.
  virtual int concurrency() const = 0;
};

// Runs every task on the calling thread, in order.
class SerialExecutor final : public Executor {
 public:
  void parallelFor(int num_tasks, TaskRef fn) override {
    for (int i = 0; i < num_tasks; ++i) fn(i);
  }
  int concurrency() const override { return 1; }
};

}  // namespace svslam
