// TokenBucket (burst, refill at a fixed rate, time passed in) and constantTimeEquals.
#include "core/token_bucket.hpp"

#include <gtest/gtest.h>

#include <cstdint>

#include "core/constant_time.hpp"

namespace svslam {
namespace {

constexpr std::int64_t kSecond = 1'000'000'000;  // ns

TEST(TokenBucket, BurstThenRefillAtTheRate) {
  TokenBucket b(10.0, 10.0);  // 10 per second, bursts of 10
  const std::int64_t t0 = 5 * kSecond;
  for (int i = 0; i < 10; ++i) EXPECT_TRUE(b.take(t0)) << i;
  EXPECT_FALSE(b.take(t0));
  EXPECT_FALSE(b.take(t0 + kSecond / 10 - 1));  // 0.99999999 token
  EXPECT_TRUE(b.take(t0 + kSecond / 10));       // one token per 100 ms
  EXPECT_FALSE(b.take(t0 + kSecond / 10));
  // Three tokens after 300 ms more.
  const std::int64_t t1 = t0 + 4 * kSecond / 10;
  EXPECT_TRUE(b.take(t1));
  EXPECT_TRUE(b.take(t1));
  EXPECT_TRUE(b.take(t1));
  EXPECT_FALSE(b.take(t1));
  // A long pause refills to the burst, not beyond.
  const std::int64_t t2 = t1 + 100 * kSecond;
  int admitted = 0;
  for (int i = 0; i < 50; ++i) admitted += b.take(t2) ? 1 : 0;
  EXPECT_EQ(admitted, 10);
}

TEST(TokenBucket, SteadyFloodIsCutToTheRate) {
  TokenBucket b(2.0, 2.0);
  int admitted = 0;
  // 1000 events per second for 10 s: 2 (burst) + 2 per second.
  for (std::int64_t t = 0; t < 10 * kSecond; t += kSecond / 1000) admitted += b.take(t) ? 1 : 0;
  EXPECT_GE(admitted, 21);
  EXPECT_LE(admitted, 22);
}

TEST(TokenBucket, TimeGoingBackwardsAddsNothing) {
  TokenBucket b(1.0, 1.0);
  EXPECT_TRUE(b.take(10 * kSecond));
  EXPECT_FALSE(b.take(0));
  EXPECT_FALSE(b.take(10 * kSecond));
  EXPECT_TRUE(b.take(11 * kSecond));
}

TEST(ConstantTimeEquals, EqualOnlyForTheSameBytes) {
  EXPECT_TRUE(constantTimeEquals("secret-token", "secret-token"));
  EXPECT_FALSE(constantTimeEquals("secret-tokeN", "secret-token"));
  EXPECT_FALSE(constantTimeEquals("Secret-token", "secret-token"));
  EXPECT_FALSE(constantTimeEquals("secret-toke", "secret-token"));    // prefix
  EXPECT_FALSE(constantTimeEquals("secret-token2", "secret-token"));  // longer
  EXPECT_FALSE(constantTimeEquals("", "secret-token"));
  EXPECT_TRUE(constantTimeEquals("", ""));
  EXPECT_FALSE(constantTimeEquals(std::string_view("a\0b", 3), std::string_view("a\0c", 3)));
}

}  // namespace
}  // namespace svslam
