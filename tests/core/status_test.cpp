// Status / Result: values, codes and messages.
#include "core/status.hpp"

#include <gtest/gtest.h>

#include <string>

#include "core/executor.hpp"

namespace svslam {
namespace {

Result<int> half(int v) {
  if (v % 2 != 0) return Status::invalidArgument("odd value " + std::to_string(v));
  return v / 2;
}

TEST(Status, OkAndErrors) {
  EXPECT_TRUE(Status::ok().isOk());
  const Status s = Status::notFound("no such file: a.png");
  EXPECT_FALSE(s.isOk());
  EXPECT_EQ(s.code(), StatusCode::kNotFound);
  EXPECT_EQ(s.message(), "no such file: a.png");
}

TEST(Result, HoldsValueOrStatus) {
  auto a = half(4);
  ASSERT_TRUE(a.isOk());
  EXPECT_EQ(*a, 2);
  EXPECT_TRUE(a.status().isOk());
  auto b = half(3);
  ASSERT_FALSE(b.isOk());
  EXPECT_EQ(b.status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(b.status().message(), "odd value 3");
}

TEST(SerialExecutor, RunsTasksInOrder) {
  SerialExecutor ex;
  std::string order;
  ex.parallelFor(4, [&](int i) { order += static_cast<char>('0' + i); });
  EXPECT_EQ(order, "0123");
  EXPECT_EQ(ex.concurrency(), 1);
}

}  // namespace
}  // namespace svslam
