// pose_correction_t: round trip, splitting into parts, and untrusted bytes (truncated, resized,
// bad counts, non-unit quaternions) rejected with a message, never a crash.
#include "drivers/lcm/lcm_pose_correction.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <random>

using namespace svslam;
using namespace svslam::drivers;

namespace {

PoseCorrectionMessage sample(int n) {
  PoseCorrectionMessage m;
  m.t_ns = 123456789000;
  m.correction_seq = 7;
  m.loops_accepted = 3;
  m.keyframes_total = n + 5;
  for (int k = 0; k < n; ++k) {
    Eigen::Isometry3d C = Eigen::Isometry3d::Identity();
    C.linear() = Eigen::AngleAxisd(0.01 * k, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
    C.translation() = Eigen::Vector3d(0.1 * k, -0.02 * k, 0.003);
    m.keyframe_t_ns.push_back(1000000LL * (k + 1));
    m.correction.push_back(C);
  }
  return m;
}

TEST(LcmPoseCorrectionTest, RoundTrip) {
  const PoseCorrectionMessage m = sample(5);
  std::vector<std::uint8_t> bytes;
  ASSERT_TRUE(encodePoseCorrection(m, bytes).isOk());
  PoseCorrectionMessage d;
  const Status s = decodePoseCorrection(bytes.data(), bytes.size(), d);
  ASSERT_TRUE(s.isOk()) << s.message();
  EXPECT_EQ(d.t_ns, m.t_ns);
  EXPECT_EQ(d.correction_seq, 7);
  EXPECT_EQ(d.loops_accepted, 3);
  EXPECT_EQ(d.keyframes_total, 10);
  EXPECT_EQ(d.frame_id, "svslam_world");
  ASSERT_EQ(d.correction.size(), 5u);
  for (int k = 0; k < 5; ++k) {
    EXPECT_EQ(d.keyframe_t_ns[static_cast<std::size_t>(k)], m.keyframe_t_ns[static_cast<std::size_t>(k)]);
    EXPECT_TRUE(d.correction[static_cast<std::size_t>(k)].isApprox(m.correction[static_cast<std::size_t>(k)], 1e-12));
  }
}

TEST(LcmPoseCorrectionTest, LargeCorrectionsAreSplitIntoParts) {
  const PoseCorrectionMessage m = sample(kMaxCorrectionKeyframesPerPart + 10);
  const std::vector<PoseCorrectionMessage> parts = splitPoseCorrection(m);
  ASSERT_EQ(parts.size(), 2u);
  EXPECT_EQ(parts[0].keyframe_t_ns.size(), static_cast<std::size_t>(kMaxCorrectionKeyframesPerPart));
  EXPECT_EQ(parts[1].keyframe_t_ns.size(), 10u);
  EXPECT_EQ(parts[1].part, 1);
  EXPECT_EQ(parts[1].parts, 2);
  std::vector<std::uint8_t> bytes;
  EXPECT_FALSE(encodePoseCorrection(m, bytes).isOk());  // too many for one part
  for (const auto& p : parts) EXPECT_TRUE(encodePoseCorrection(p, bytes).isOk());
}

TEST(LcmPoseCorrectionTest, BadReportsAreRefused) {
  PoseCorrectionMessage m = sample(2);
  m.correction[1].linear() *= 2.0;  // not a rotation
  std::vector<std::uint8_t> bytes;
  EXPECT_EQ(encodePoseCorrection(m, bytes).code(), StatusCode::kInvalidArgument);
  m = sample(2);
  m.keyframe_t_ns[1] = m.keyframe_t_ns[0];
  EXPECT_FALSE(encodePoseCorrection(m, bytes).isOk());
  m = sample(2);
  m.part = 2;
  EXPECT_FALSE(encodePoseCorrection(m, bytes).isOk());
}

TEST(LcmPoseCorrectionTest, UntrustedBytesNeverCrash) {
  std::vector<std::uint8_t> good;
  ASSERT_TRUE(encodePoseCorrection(sample(3), good).isOk());
  PoseCorrectionMessage out;
  for (std::size_t n = 0; n < good.size(); ++n)
    EXPECT_EQ(decodePoseCorrection(good.data(), n, out).code(), StatusCode::kCorruptData) << n;
  std::vector<std::uint8_t> longer = good;
  longer.push_back(0);
  EXPECT_EQ(decodePoseCorrection(longer.data(), longer.size(), out).code(), StatusCode::kCorruptData);
  // A huge keyframe count is refused before anything is allocated.
  std::vector<std::uint8_t> big = good;
  const std::size_t n_at = 36 + std::strlen("svslam_world") + 1 + 8;
  big[n_at] = 0x7f;
  EXPECT_EQ(decodePoseCorrection(big.data(), big.size(), out).code(), StatusCode::kCorruptData);
  // A quaternion scaled off the unit sphere.
  std::vector<std::uint8_t> bad = good;
  bad[bad.size() - 8] ^= 0x40;  // the exponent of the last quaternion component
  EXPECT_FALSE(decodePoseCorrection(bad.data(), bad.size(), out).isOk());
  // A time whose nanoseconds overflow int64 (utime = bytes 8..15, big-endian).
  std::vector<std::uint8_t> late = good;
  late[8] = 0x7f;
  EXPECT_EQ(decodePoseCorrection(late.data(), late.size(), out).code(), StatusCode::kCorruptData);
  std::mt19937 rng(5);
  for (int i = 0; i < 2000; ++i) {
    std::vector<std::uint8_t> b = good;
    b[rng() % b.size()] = static_cast<std::uint8_t>(rng());
    (void)decodePoseCorrection(b.data(), b.size(), out);  // must not crash
  }
}

}  // namespace
