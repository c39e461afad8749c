// svslam_lcm.altitude_t <-> AltitudeReading: a reading goes through the wire unchanged; bytes
// that are not a valid reading are rejected with a message naming the problem.
#include "drivers/lcm/lcm_altitude.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "drivers/lcm/lcm_messages.hpp"

namespace svslam::drivers {
namespace {

std::vector<std::uint8_t> bytesOf(const svslam_lcm::altitude_t& m) {
  std::vector<std::uint8_t> b;
  EXPECT_TRUE(encodeLcm(m, b).isOk());
  return b;
}

TEST(LcmAltitude, ReadingGoesThroughTheWire) {
  auto m = toLcm(AltitudeReading{1'234'567'000, 27.25, 0.15});
  ASSERT_TRUE(m.isOk()) << m.status().message();
  const std::vector<std::uint8_t> b = bytesOf(*m);
  AltitudeReading r;
  ASSERT_TRUE(decodeAltitude(b.data(), b.size(), r).isOk());
  EXPECT_EQ(r.t_ns, 1'234'567'000);
  EXPECT_EQ(r.altitude_m, 27.25);
  EXPECT_EQ(r.sigma_m, 0.15);
}

TEST(LcmAltitude, OutOfRangeValuesAreRefusedByName) {
  EXPECT_NE(toLcm(AltitudeReading{0, 0.0, 0.1}).status().message().find("altitude_m"),
            std::string::npos);
  EXPECT_NE(toLcm(AltitudeReading{0, 10.0, -1.0}).status().message().find("sigma_m"),
            std::string::npos);
  svslam_lcm::altitude_t m;
  m.utime = 0;
  m.sigma_m = 0.1;
  const AltitudeReading untouched{7, 3.0, 0.5};
  for (double a : {std::nan(""), -2.0, 0.0, std::numeric_limits<double>::infinity()}) {
    m.altitude_m = a;
    const std::vector<std::uint8_t> b = bytesOf(m);
    AltitudeReading r = untouched;
    const Status s = decodeAltitude(b.data(), b.size(), r);
    EXPECT_FALSE(s.isOk()) << a;
    EXPECT_NE(s.message().find("altitude_m"), std::string::npos) << s.message();
    EXPECT_EQ(r.altitude_m, 3.0);  // untouched
  }
  m.altitude_m = 10;
  m.sigma_m = std::nan("");
  std::vector<std::uint8_t> b = bytesOf(m);
  AltitudeReading r;
  EXPECT_NE(decodeAltitude(b.data(), b.size(), r).message().find("sigma_m"), std::string::npos);
  m.sigma_m = 0.1;
  m.utime = std::numeric_limits<std::int64_t>::max();
  b = bytesOf(m);
  EXPECT_NE(decodeAltitude(b.data(), b.size(), r).message().find("overflows"), std::string::npos);
}

TEST(LcmAltitude, GarbageTruncatedAndOtherTypesAreCorruptData) {
  auto m = toLcm(AltitudeReading{0, 27.0, 0.1});
  ASSERT_TRUE(m.isOk());
  std::vector<std::uint8_t> b = bytesOf(*m);
  AltitudeReading r;
  EXPECT_EQ(decodeAltitude(b.data(), b.size() - 1, r).code(), StatusCode::kCorruptData);
  b.push_back(0);
  EXPECT_EQ(decodeAltitude(b.data(), b.size(), r).code(), StatusCode::kCorruptData);
  const std::uint8_t garbage[] = {'g', 'a', 'r', 'b', 'a', 'g', 'e'};
  EXPECT_EQ(decodeAltitude(garbage, sizeof garbage, r).code(), StatusCode::kCorruptData);
  EXPECT_EQ(decodeAltitude(nullptr, 0, r).code(), StatusCode::kCorruptData);
  svslam_lcm::command_t other;  // another type: its hash differs
  other.utime = 0;
  other.seq = 1;
  other.command = "reset";
  std::vector<std::uint8_t> ob;
  ASSERT_TRUE(encodeLcm(other, ob).isOk());
  const Status s = decodeAltitude(ob.data(), ob.size(), r);
  EXPECT_EQ(s.code(), StatusCode::kCorruptData);
  EXPECT_NE(s.message().find("altitude_t"), std::string::npos) << s.message();
}

}  // namespace
}  // namespace svslam::drivers
