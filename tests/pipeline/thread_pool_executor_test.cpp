// ThreadPoolExecutor: every task runs exactly once, for any task and thread count, repeatedly.
#include "pipeline/thread_pool_executor.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <vector>

namespace svslam {
namespace {

TEST(ThreadPoolExecutor, RunsEveryTaskOnce) {
  for (int threads : {1, 2, 4}) {
    ThreadPoolExecutor ex(threads);
    EXPECT_EQ(ex.concurrency(), threads);
    for (int n : {0, 1, 3, 17, 100}) {
      for (int rep = 0; rep < 20; ++rep) {
        std::vector<std::atomic<int>> hits(static_cast<std::size_t>(n));
        ex.parallelFor(n, [&](int i) { hits[static_cast<std::size_t>(i)].fetch_add(1); });
        for (int i = 0; i < n; ++i)
          ASSERT_EQ(hits[static_cast<std::size_t>(i)].load(), 1) << threads << " " << n;
      }
    }
  }
}

}  // namespace
}  // namespace svslam
