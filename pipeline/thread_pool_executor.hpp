#pragma once
// ThreadPoolExecutor: a fixed pool of worker threads behind the Executor interface of src/core.
// parallelFor hands out task indices to the workers and the calling thread; it blocks until
// every task is done. Threads start in the constructor and are joined in the destructor.
#include <condition_variable>
#include <mutex>
#include <thread>
#include <vector>

#include "core/executor.hpp"

namespace svslam {

class ThreadPoolExecutor final : public Executor {
 public:
  // num_threads >= 1 counts the calling thread: num_threads - 1 workers are started.
  explicit ThreadPoolExecutor(int num_threads);
  ~ThreadPoolExecutor() override;
  ThreadPoolExecutor(const ThreadPoolExecutor&) = delete;
  ThreadPoolExecutor& operator=(const ThreadPoolExecutor&) = delete;

  void parallelFor(int num_tasks, TaskRef fn) override;
  int concurrency() const override { return static_cast<int>(workers_.size()) + 1; }

 private:
  void workerLoop();
  void runTasks();

  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::condition_variable done_;
  const TaskRef* fn_ = nullptr;  // the running call's tasks
  int num_tasks_ = 0;
  int next_task_ = 0;
  int unfinished_ = 0;
  unsigned generation_ = 0;
  bool stop_ = false;
  std::mutex call_mutex_;  // one parallelFor at a time
};

}  // namespace svslam
