// libcamera: source without camera hardware: clean errors listing the cameras found.
#include <gtest/gtest.h>

#include <string>

#include "drivers/source/stereo_source.hpp"

namespace svslam::drivers {
namespace {

bool notBuilt(const Status& s) {
  return s.message().find("libcamera support not built") != std::string::npos;
}

TEST(LibcameraSource, UnknownCameraIsACleanErrorListingCameras) {
  auto r = openStereoSource("libcamera:no-such-cam,other?width=640&height=480");
  ASSERT_FALSE(r);
  if (notBuilt(r.status())) GTEST_SKIP() << "built without libcamera";
  EXPECT_EQ(r.status().code(), StatusCode::kNotFound);
  const std::string& m = r.status().message();
  EXPECT_EQ(m.rfind("libcamera: camera 'no-such-cam' not found (", 0), 0u) << m;
  EXPECT_NE(m.find(" cameras"), std::string::npos) << m;
  // Twice in a row: the camera manager of the first attempt was released.
  auto again = openStereoSource("libcamera:no-such-cam,other");
  ASSERT_FALSE(again);
  EXPECT_EQ(again.status().message(), m);
}

TEST(LibcameraSource, BadSpecsAreRejectedBeforeTouchingCameras) {
  auto unknown = openStereoSource("libcamera:a,b?exposure=3");
  ASSERT_FALSE(unknown);
  if (notBuilt(unknown.status())) GTEST_SKIP() << "built without libcamera";
  EXPECT_EQ(unknown.status().message(), "libcamera: unknown option 'exposure'");
  auto one = openStereoSource("libcamera:a");
  ASSERT_FALSE(one);
  EXPECT_NE(one.status().message().find("two camera ids"), std::string::npos);
  auto empty = openStereoSource("libcamera:");
  ASSERT_FALSE(empty);
  EXPECT_NE(empty.status().message().find("no camera given"), std::string::npos);
  auto size = openStereoSource("libcamera:a,b?width=abc");
  ASSERT_FALSE(size);
  EXPECT_EQ(size.status().code(), StatusCode::kInvalidArgument);
  auto frozen = openStereoSource("libcamera:a,b?frozen_frames=1");
  ASSERT_FALSE(frozen);
  EXPECT_EQ(frozen.status().message(),
            "libcamera: option frozen_frames must be 0 (off) or in [2, 1000000], got 1");
  auto action = openStereoSource("libcamera:a,b?frozen_action=ignore");
  ASSERT_FALSE(action);
  EXPECT_EQ(action.status().message(),
            "libcamera: option frozen_action must be 'error' or 'warn', got 'ignore'");
  // Valid fault options pass the spec check and fail only on the missing cameras.
  auto ok = openStereoSource("libcamera:a,b?frozen_frames=0&frozen_action=warn");
  ASSERT_FALSE(ok);
  EXPECT_EQ(ok.status().code(), StatusCode::kNotFound) << ok.status().message();
}

}  // namespace
}  // namespace svslam::drivers
