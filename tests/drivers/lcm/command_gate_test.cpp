// CommandGate: disabled by default, token required and compared, rate limit after the token
// check, every outcome counted by reason; CommandAuthParams::validate.
#include "drivers/lcm/command_gate.hpp"

#include <gtest/gtest.h>

#include <cstdint>

namespace svslam::drivers {
namespace {

constexpr std::int64_t kSecond = 1'000'000'000;  // ns
const char* kToken = "s3cret-token-of-the-service";

TEST(CommandGate, DefaultRefusesEverythingAsDisabled) {
  CommandGate g;
  EXPECT_FALSE(g.enabled());
  EXPECT_EQ(g.admit(kToken, 0), CommandRefusal::kDisabled);
  EXPECT_EQ(g.admit("", 0), CommandRefusal::kDisabled);
  EXPECT_EQ(g.counts().refusedBy(CommandRefusal::kDisabled), 2);
  EXPECT_EQ(g.counts().accepted, 0);
}

TEST(CommandGate, EnabledWithoutTokenStaysDisabled) {
  CommandGate g(true, "", 10.0);
  EXPECT_FALSE(g.enabled());
  EXPECT_EQ(g.admit("", 0), CommandRefusal::kDisabled);
}

TEST(CommandGate, TokenAcceptedOrRefused) {
  CommandGate g(true, kToken, 10.0);
  EXPECT_TRUE(g.enabled());
  EXPECT_EQ(g.admit(kToken, 0), std::nullopt);
  EXPECT_EQ(g.admit("", 0), CommandRefusal::kNoToken);
  EXPECT_EQ(g.admit("s3cret-token-of-the-servicE", 0), CommandRefusal::kBadToken);
  EXPECT_EQ(g.admit("s3cret", 0), CommandRefusal::kBadToken);
  EXPECT_EQ(g.counts().accepted, 1);
  EXPECT_EQ(g.counts().refusedBy(CommandRefusal::kNoToken), 1);
  EXPECT_EQ(g.counts().refusedBy(CommandRefusal::kBadToken), 2);
  EXPECT_EQ(g.counts().refusedTotal(), 3);
}

TEST(CommandGate, RateLimitBurstThenRefill) {
  CommandGate g(true, kToken, 4.0);  // 4 per second, bursts of 4
  const std::int64_t t0 = 100 * kSecond;
  for (int i = 0; i < 4; ++i) EXPECT_EQ(g.admit(kToken, t0), std::nullopt) << i;
  EXPECT_EQ(g.admit(kToken, t0), CommandRefusal::kRateLimited);
  EXPECT_EQ(g.admit(kToken, t0 + kSecond / 4 - 1), CommandRefusal::kRateLimited);
  EXPECT_EQ(g.admit(kToken, t0 + kSecond / 4), std::nullopt);  // one token per 250 ms
  EXPECT_EQ(g.admit(kToken, t0 + kSecond / 4), CommandRefusal::kRateLimited);
  EXPECT_EQ(g.counts().accepted, 5);
  EXPECT_EQ(g.counts().refusedBy(CommandRefusal::kRateLimited), 3);
}

TEST(CommandGate, UnauthenticatedFloodDoesNotUseTheBudget) {
  CommandGate g(true, kToken, 1.0);
  for (int i = 0; i < 1000; ++i) EXPECT_EQ(g.admit("guess", 0), CommandRefusal::kBadToken);
  EXPECT_EQ(g.admit(kToken, 0), std::nullopt);
  EXPECT_EQ(g.counts().refusedBy(CommandRefusal::kRateLimited), 0);
}

TEST(CommandAuthParams, Validate) {
  CommandAuthParams p;
  EXPECT_TRUE(p.validate().isOk());  // disabled by default
  EXPECT_FALSE(p.enabled);
  EXPECT_EQ(p.max_per_s, 10.0);
  p.enabled = true;
  const Status no_file = p.validate();
  EXPECT_FALSE(no_file.isOk());
  EXPECT_NE(no_file.message().find("token_file"), std::string::npos) << no_file.message();
  p.token_file = "/etc/svslam/command.token";
  EXPECT_TRUE(p.validate().isOk());
  p.max_per_s = 0.0;
  EXPECT_FALSE(p.validate().isOk());
}

// Counts decoded from a stats_t of the wire overflowed int64 when summed (found by
// fuzz_lcm_listen): the total saturates.
TEST(CommandGate, RefusedTotalSaturates) {
  CommandCounts c;
  c.refused.fill(INT64_MAX / 2 + 1);
  EXPECT_EQ(c.refusedTotal(), INT64_MAX);
  c.refused.fill(0);
  c.refused[0] = 3;
  c.refused[1] = 4;
  EXPECT_EQ(c.refusedTotal(), 7);
}

}  // namespace
}  // namespace svslam::drivers
