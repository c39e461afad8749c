#pragma once
// Executor: how a pure library stage runs independent tasks (row stripes) in parallel without
// owning threads. The stage decides the tasks; the caller injects the executor. Results must
// not depend on which executor or how many tasks are used.
#include <functional>

namespace svslam {

class Executor {
 public:
  virtual ~Executor() = default;
  // Runs fn(0) .. fn(num_tasks - 1), possibly concurrently, and returns when all are done.
  virtual void parallelFor(int num_tasks, const std::function<void(int)>& fn) = 0;
  // How many tasks can usefully run at once.
  virtual int concurrency() const = 0;
};

// Runs every task on the calling thread, in order.
class SerialExecutor final : public Executor {
 public:
  void parallelFor(int num_tasks, const std::function<void(int)>& fn) override {
    for (int i = 0; i < num_tasks; ++i) fn(i);
  }
  int concurrency() const override { return 1; }
};

}  // namespace svslam
