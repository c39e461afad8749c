#pragma once
// Test executor: runs the tasks concurrently on their own threads, last first (stages must give
// the same results for any executor and any order).
#include <thread>
#include <vector>

#include "core/executor.hpp"

namespace svslam::test_support {

class SpawningExecutor final : public Executor {
 public:
  explicit SpawningExecutor(int n) : n_(n) {}
  void parallelFor(int num_tasks, TaskRef fn) override {
    std::vector<std::thread> threads;
    for (int i = num_tasks - 1; i >= 0; --i) threads.emplace_back(fn, i);
    for (auto& t : threads) t.join();
  }
  int concurrency() const override { return n_; }

 private:
  int n_;
};

}  // namespace svslam::test_support
