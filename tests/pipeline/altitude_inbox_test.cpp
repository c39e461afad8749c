// AltitudeInbox: a frame gets the latest altimeter reading taken at or before its capture time,
// whatever the order the readings arrived in; none before the first reading.
#include "pipeline/realtime/altitude_inbox.hpp"

#include <gtest/gtest.h>

#include <thread>

namespace svslam::rt {
namespace {

TEST(AltitudeInbox, LatestReadingAtOrBeforeTheFrame) {
  AltitudeInbox box;
  double a = -1;
  EXPECT_FALSE(box.latestAtOrBefore(1000, a));
  box.push(100, 10.0);
  box.push(300, 30.0);
  box.push(200, 20.0);  // late arrival
  EXPECT_FALSE(box.latestAtOrBefore(99, a));
  EXPECT_EQ(a, -1);
  ASSERT_TRUE(box.latestAtOrBefore(100, a));
  EXPECT_EQ(a, 10.0);
  ASSERT_TRUE(box.latestAtOrBefore(250, a));
  EXPECT_EQ(a, 20.0);
  ASSERT_TRUE(box.latestAtOrBefore(1000, a));
  EXPECT_EQ(a, 30.0);
  box.push(300, 31.0);  // same time: the one received last
  ASSERT_TRUE(box.latestAtOrBefore(300, a));
  EXPECT_EQ(a, 31.0);
  box.reject();
  EXPECT_EQ(box.accepted(), 4);
  EXPECT_EQ(box.rejected(), 1);
}

TEST(AltitudeInbox, KeepsTheLastCapacityReadings) {
  AltitudeInbox box;
  const int n = static_cast<int>(AltitudeInbox::kCapacity) + 10;
  for (int k = 0; k < n; ++k) box.push(k, static_cast<double>(k));
  double a = 0;
  EXPECT_FALSE(box.latestAtOrBefore(9, a));  // the first ten were dropped
  ASSERT_TRUE(box.latestAtOrBefore(10, a));
  EXPECT_EQ(a, 10.0);
  ASSERT_TRUE(box.latestAtOrBefore(n, a));
  EXPECT_EQ(a, static_cast<double>(n - 1));
}

TEST(AltitudeInbox, WritersAndAReaderOnOtherThreads) {
  AltitudeInbox box;
  std::thread w([&] {
    for (int k = 1; k <= 2000; ++k) box.push(k, static_cast<double>(k));
  });
  double a = 0, last = 0;
  for (int i = 0; i < 2000; ++i)
    if (box.latestAtOrBefore(1'000'000, a)) {
      EXPECT_GE(a, last);  // readings pushed in time order: never goes back
      last = a;
    }
  w.join();
  ASSERT_TRUE(box.latestAtOrBefore(1'000'000, a));
  EXPECT_EQ(a, 2000.0);
}

}  // namespace
}  // namespace svslam::rt
