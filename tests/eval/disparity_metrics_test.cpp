#include "eval/disparity_metrics.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

namespace svslam {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kNan = std::numeric_limits<float>::quiet_NaN();

ImageF32 makeF32(int w, int h, std::initializer_list<float> values) {
  ImageF32 img(w, h);
  auto it = values.begin();
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) img(x, y) = *it++;
  return img;
}

TEST(DisparityMetrics, PerfectEstimate) {
  const ImageF32 gt = makeF32(3, 1, {10.0f, 20.0f, 30.0f});
  const Result<DisparityMetrics> r = evaluateDisparity(gt.cview(), gt.cview(), {});
  ASSERT_TRUE(r.isOk()) << r.status().message();
  EXPECT_EQ(r->evaluated, 3);
  EXPECT_EQ(r->valid, 3);
  EXPECT_DOUBLE_EQ(r->density_pct, 100.0);
  EXPECT_DOUBLE_EQ(r->bad05_all_pct, 0.0);
  EXPECT_DOUBLE_EQ(r->bad3_valid_pct, 0.0);
  EXPECT_DOUBLE_EQ(r->mae_valid_px, 0.0);
  EXPECT_DOUBLE_EQ(r->rmse_valid_px, 0.0);
}

// gt known at 8 of 10 pixels (0 and inf are unknown); the estimate misses 2 of them (inf, NaN).
// Errors on the 6 valid pixels: 0, 0.5, 1, 2, 3, 4 px -- thresholds are strict, so an error of
// exactly N is not bad-N.
TEST(DisparityMetrics, HandComputedCase) {
  const ImageF32 gt = makeF32(5, 2,
                              {10, 10, 10, 10, 10,  //
                               10, 10, 10, 0, kInf});
  const ImageF32 est = makeF32(5, 2,
                               {10.0f, 10.5f, 9.0f, 12.0f, 13.0f,  //
                                14.0f, kInf, kNan, 5.0f, 5.0f});
  const Result<DisparityMetrics> r = evaluateDisparity(est.cview(), gt.cview(), {});
  ASSERT_TRUE(r.isOk()) << r.status().message();
  EXPECT_EQ(r->evaluated, 8);
  EXPECT_EQ(r->valid, 6);
  EXPECT_DOUBLE_EQ(r->density_pct, 75.0);
  // errors > 0.5: {1, 2, 3, 4} = 4; > 1: {2, 3, 4} = 3; > 2: {3, 4} = 2; > 3: {4} = 1.
  EXPECT_DOUBLE_EQ(r->bad05_valid_pct, 100.0 * 4 / 6);
  EXPECT_DOUBLE_EQ(r->bad1_valid_pct, 100.0 * 3 / 6);
  EXPECT_DOUBLE_EQ(r->bad2_valid_pct, 100.0 * 2 / 6);
  EXPECT_DOUBLE_EQ(r->bad3_valid_pct, 100.0 * 1 / 6);
  EXPECT_DOUBLE_EQ(r->bad05_all_pct, 100.0 * (2 + 4) / 8);
  EXPECT_DOUBLE_EQ(r->bad1_all_pct, 100.0 * (2 + 3) / 8);
  EXPECT_DOUBLE_EQ(r->bad2_all_pct, 100.0 * (2 + 2) / 8);
  EXPECT_DOUBLE_EQ(r->bad3_all_pct, 100.0 * (2 + 1) / 8);
  EXPECT_DOUBLE_EQ(r->mae_valid_px, (0 + 0.5 + 1 + 2 + 3 + 4) / 6.0);
  EXPECT_DOUBLE_EQ(r->rmse_valid_px, std::sqrt((0 + 0.25 + 1 + 4 + 9 + 16) / 6.0));
}

TEST(DisparityMetrics, MaskRestrictsEvaluation) {
  const ImageF32 gt = makeF32(4, 1, {10, 10, 10, 10});
  const ImageF32 est = makeF32(4, 1, {10, 20, kInf, 10.25f});
  ImageU8 mask(4, 1);
  mask(0, 0) = 255;
  mask(1, 0) = 0;  // the gross error is masked out
  mask(2, 0) = 1;  // any nonzero value means evaluate
  mask(3, 0) = 255;
  const Result<DisparityMetrics> r = evaluateDisparity(est.cview(), gt.cview(), mask.cview());
  ASSERT_TRUE(r.isOk()) << r.status().message();
  EXPECT_EQ(r->evaluated, 3);
  EXPECT_EQ(r->valid, 2);
  EXPECT_NEAR(r->density_pct, 200.0 / 3.0, 1e-12);
  EXPECT_DOUBLE_EQ(r->bad05_valid_pct, 0.0);
  EXPECT_NEAR(r->bad05_all_pct, 100.0 / 3.0, 1e-12);
  EXPECT_DOUBLE_EQ(r->mae_valid_px, 0.125);
}

TEST(DisparityMetrics, RespectsStrideOfViews) {
  // A 2x2 view inside a 4x3 buffer: the pixels outside the view must be ignored.
  ImageF32 big_gt(4, 3);
  ImageF32 big_est(4, 3);
  big_gt.fill(5.0f);
  big_est.fill(100.0f);
  for (int y = 1; y < 3; ++y)
    for (int x = 1; x < 3; ++x) big_est(x, y) = 5.0f;
  const Result<DisparityMetrics> r =
      evaluateDisparity(big_est.cview().sub(1, 1, 2, 2), big_gt.cview().sub(1, 1, 2, 2), {});
  ASSERT_TRUE(r.isOk());
  EXPECT_EQ(r->evaluated, 4);
  EXPECT_DOUBLE_EQ(r->bad05_all_pct, 0.0);
}

TEST(DisparityMetrics, NoValidPixelGivesZeroStatisticsNotNan) {
  const ImageF32 gt = makeF32(2, 1, {3, 4});
  const ImageF32 est = makeF32(2, 1, {kInf, kNan});
  const Result<DisparityMetrics> r = evaluateDisparity(est.cview(), gt.cview(), {});
  ASSERT_TRUE(r.isOk());
  EXPECT_EQ(r->valid, 0);
  EXPECT_DOUBLE_EQ(r->density_pct, 0.0);
  EXPECT_DOUBLE_EQ(r->bad1_valid_pct, 0.0);
  EXPECT_DOUBLE_EQ(r->bad1_all_pct, 100.0);
  EXPECT_DOUBLE_EQ(r->mae_valid_px, 0.0);
  EXPECT_DOUBLE_EQ(r->rmse_valid_px, 0.0);
  const std::string json = toJson(r.value());
  EXPECT_EQ(json.find("nan"), std::string::npos) << json;
}

TEST(DisparityMetrics, SizeMismatchNamesBothSizes) {
  const ImageF32 a(4, 3);
  const ImageF32 b(3, 4);
  const Result<DisparityMetrics> r = evaluateDisparity(a.cview(), b.cview(), {});
  ASSERT_FALSE(r.isOk());
  EXPECT_EQ(r.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(r.status().message().find("4x3"), std::string::npos) << r.status().message();
  EXPECT_NE(r.status().message().find("3x4"), std::string::npos) << r.status().message();
}

TEST(DisparityMetrics, MaskSizeMismatch) {
  const ImageF32 a = makeF32(2, 1, {1, 1});
  const ImageU8 mask(3, 1);
  const Result<DisparityMetrics> r = evaluateDisparity(a.cview(), a.cview(), mask.cview());
  ASSERT_FALSE(r.isOk());
  EXPECT_EQ(r.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(r.status().message().find("3x1"), std::string::npos) << r.status().message();
  EXPECT_NE(r.status().message().find("2x1"), std::string::npos) << r.status().message();
}

TEST(DisparityMetrics, EmptyImagesAndNoEvaluatedPixelAreErrors) {
  const ImageF32 empty;
  EXPECT_EQ(evaluateDisparity(empty.cview(), empty.cview(), {}).status().code(),
            StatusCode::kInvalidArgument);
  // Ground truth unknown everywhere (0, negative, inf, NaN).
  const ImageF32 gt = makeF32(4, 1, {0, -1, kInf, kNan});
  const ImageF32 est = makeF32(4, 1, {1, 1, 1, 1});
  EXPECT_EQ(evaluateDisparity(est.cview(), gt.cview(), {}).status().code(),
            StatusCode::kInvalidArgument);
  // Known ground truth, but the mask excludes everything.
  const ImageF32 gt2 = makeF32(2, 1, {1, 2});
  const ImageU8 zeros(2, 1);  // zero-initialised
  EXPECT_EQ(evaluateDisparity(gt2.cview(), gt2.cview(), zeros.cview()).status().code(),
            StatusCode::kInvalidArgument);
}

TEST(DisparityMetrics, JsonIsFlatFixedFourDecimals) {
  DisparityMetrics m;
  m.evaluated = 8;
  m.valid = 6;
  m.density_pct = 75.0;
  m.bad1_valid_pct = 100.0 / 3.0;
  m.mae_valid_px = 1.75;
  const std::string json = toJson(m);
  EXPECT_EQ(json.front(), '{');
  EXPECT_EQ(json.back(), '}');
  EXPECT_NE(json.find("\"evaluated\": 8,"), std::string::npos) << json;
  EXPECT_NE(json.find("\"valid\": 6,"), std::string::npos) << json;
  EXPECT_NE(json.find("\"density_pct\": 75.0000"), std::string::npos) << json;
  EXPECT_NE(json.find("\"bad1_valid_pct\": 33.3333"), std::string::npos) << json;
  EXPECT_NE(json.find("\"mae_valid_px\": 1.7500"), std::string::npos) << json;
  for (const char* key : {"bad05_valid_pct", "bad2_valid_pct", "bad3_valid_pct", "bad05_all_pct",
                          "bad1_all_pct", "bad2_all_pct", "bad3_all_pct", "rmse_valid_px"}) {
    EXPECT_NE(json.find(std::string("\"") + key + "\": 0.0000"), std::string::npos) << key;
  }
  EXPECT_EQ(json.find('{', 1), std::string::npos) << "nested object in " << json;
}

TEST(DisparityMetrics, JsonNeverPrintsNanOrInf) {
  DisparityMetrics m;
  m.density_pct = std::numeric_limits<double>::quiet_NaN();
  m.mae_valid_px = std::numeric_limits<double>::infinity();
  const std::string json = toJson(m);
  EXPECT_EQ(json.find("nan"), std::string::npos) << json;
  EXPECT_EQ(json.find("inf"), std::string::npos) << json;
  EXPECT_NE(json.find("\"density_pct\": null"), std::string::npos) << json;
}

}  // namespace
}  // namespace svslam
