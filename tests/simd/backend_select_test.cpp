// Run-time choice of the stereo kernel backend: the best available one, names and parsing.
#include <gtest/gtest.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>
#include <vector>


#include "simd/stereo_kernels.hpp"
#include "stereo_kernels_test_support.hpp"

namespace svslam::simd {
namespace {

using namespace test_support;

class BackendSelectTest : public ::testing::TestWithParam<Backend> {};

TEST_P(BackendSelectTest, KernelsOfAnAvailableBackend) {
  const Backend b = GetParam();
  if (b == Backend::kAuto) {
    const Backend best = bestBackend();
    EXPECT_NE(best, Backend::kAuto);
    EXPECT_TRUE(backendAvailable(best));
    EXPECT_EQ(kernels(Backend::kAuto).backend, best);
    std::string available;
    for (Backend c : {Backend::kScalar, Backend::kAvx2, Backend::kAvx512, Backend::kNeon})
      if (backendAvailable(c)) available += std::string(" ") + backendName(c);
    std::printf("available backends:%s; auto -> %s\n", available.c_str(), backendName(best));
    return;
  }
  if (!backendAvailable(b)) GTEST_SKIP() << "backend " << backendName(b) << " not available";
  EXPECT_EQ(kernels(b).backend, b);
  EXPECT_STREQ(kernels(b).name, backendName(b));
}

TEST_P(BackendSelectTest, ParseAndNameRoundTrip) {
  Backend parsed = GetParam() == Backend::kScalar ? Backend::kAuto : Backend::kScalar;
  ASSERT_TRUE(parseBackend(backendName(GetParam()), parsed)) << backendName(GetParam());
  EXPECT_EQ(parsed, GetParam());
}

TEST_P(BackendSelectTest, ParseRejectsOtherNames) {
  const std::string name = backendName(GetParam());
  Backend out = GetParam();
  EXPECT_FALSE(parseBackend("", out));
  EXPECT_FALSE(parseBackend((name + " ").c_str(), out));
  EXPECT_FALSE(parseBackend(name.substr(0, name.size() - 1).c_str(), out));
  std::string upper = name;
  for (char& ch : upper) ch = static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
  EXPECT_FALSE(parseBackend(upper.c_str(), out));
  EXPECT_EQ(out, GetParam());  // untouched on failure
}

INSTANTIATE_TEST_SUITE_P(Backends, BackendSelectTest,
                         ::testing::Values(Backend::kAuto, Backend::kScalar, Backend::kAvx2,
                                           Backend::kAvx512, Backend::kNeon),
                         paramName);

}  // namespace
}  // namespace svslam::simd
