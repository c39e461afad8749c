// Stereo point matcher, row search: sub-pixel accuracy, the ratio test on periodic texture;
// checked against the rendered scene of stereo_point_matcher_scene.hpp.
#include "features/stereo_point_matcher.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "stereo_point_matcher_scene.hpp"

namespace svslam {
namespace {

using namespace stereo_scene;  // NOLINT: the shared test scene

TEST(StereoPointMatcher, SubPixelDisparityOnPlaneAndBox) {
  const Rendered& r = boxScene();
  const auto pts = randomPixels(800, r.scene.w, r.scene.h, 123);
  StereoPointMatcher matcher(defaultParams());
  ASSERT_TRUE(matcher.initStatus().isOk());
  std::vector<StereoMatch> out;
  StereoMatchStats st;
  ASSERT_TRUE(matcher.process(r.left.cview(), r.right.cview(), pts, {}, out, st).isOk());
  std::vector<double> err;
  int in_box = 0, bad = 0;
  for (std::size_t k = 0; k < out.size(); ++k) {
    const auto& m = out[k];
    if (k > 0) {
      EXPECT_LT(out[k - 1].index, m.index) << "sorted by index, no repeats";
    }
    ASSERT_GE(m.index, 0);
    EXPECT_EQ(m.u_px, pts[static_cast<std::size_t>(m.index)].x());
    EXPECT_EQ(m.v_px, pts[static_cast<std::size_t>(m.index)].y());
    EXPECT_GT(m.curvature, 0.0f);
    EXPECT_FLOAT_EQ(m.sigma_d_px, 0.3f);  // the default: fixed sigma_d
    EXPECT_GE(m.score, 0.8f);
    err.push_back(errorOf(r.scene, m));
    if (err.back() > 1.0) ++bad;
    in_box += r.scene.inBox(m.u_px, m.v_px) ? 1 : 0;
  }
  const double med = percentile(err, 0.5), p95 = percentile(err, 0.95);
  std::printf(
      "[ figures  ] stereo: candidates %d row %d continuity_rejected %d recovered %d "
      "matched %d (box %d) | error median %.3f px p95 %.3f px max %.3f px, >1px %d\n",
      st.candidates, st.row_matched, st.continuity_rejected, st.recovered, st.matched, in_box, med,
      p95, percentile(err, 1.0), bad);
  EXPECT_EQ(st.matched, static_cast<int>(out.size()));
  EXPECT_GT(st.matched, st.candidates * 7 / 10) << "most textured points matched";
  EXPECT_GT(in_box, 50);
  EXPECT_LT(med, 0.15);
  EXPECT_LT(p95, 0.5);
  EXPECT_LE(bad, static_cast<int>(out.size()) / 100) << "gross errors";
  // Candidates: every point whose 9x9 patch is inside the image.
  int inside = 0;
  for (const auto& p : pts)
    inside += (p.x() >= 4 && p.y() >= 4 && p.x() < r.scene.w - 4 && p.y() < r.scene.h - 4) ? 1 : 0;
  EXPECT_EQ(st.candidates, inside);
}

// Vertical stripes of period 8 px on a fronto-parallel part of the scene: the right image
// repeats exactly every 8 px, so the ZNCC peaks at d and d + 8 tie.
std::vector<Eigen::Vector2f> stripePoints(const Scene& s) {
  // Points whose patch and whole candidate range see only stripes: searched shifts up to
  // 63 px stay inside the stripe band of the right image for x in [s.sx0 + 68, s.sx1 - 5].
  std::vector<Eigen::Vector2f> pts;
  for (int y = s.sy0 + 6; y < s.sy1 - 6; y += 7)
    for (int x = s.sx0 + 68; x < s.sx1 - 5; x += 7) pts.emplace_back(x, y);
  return pts;
}

TEST(StereoPointMatcher, RatioTestRejectsPeriodicStripes) {
  Scene s;
  s.box = false;
  s.stripes = true;
  s.pb = 0.0;  // constant disparity along each row: exact 8 px periodicity in both images
  const ImageU8 left = s.left(), right = s.right();
  const auto stripe_pts = stripePoints(s);
  std::vector<Eigen::Vector2f> other_pts;
  for (int y = 120; y < 230; y += 11)
    for (int x = 70; x < 310; x += 11) other_pts.emplace_back(x, y);
  auto run = [&](float ratio, const std::vector<Eigen::Vector2f>& pts) {
    StereoMatchParams p = defaultParams();
    p.ratio = ratio;
    if (ratio >= 1.0f) p.ratio_floor = 0.0f;  // no ratio test at all
    p.continuity_check = false;
    StereoPointMatcher matcher(p);
    std::vector<StereoMatch> out;
    StereoMatchStats st;
    EXPECT_TRUE(matcher.process(left.cview(), right.cview(), pts, {}, out, st).isOk());
    return out;
  };
  const auto stripes_default = run(0.8f, stripe_pts);
  const auto stripes_no_ratio = run(1.0f, stripe_pts);
  const auto others = run(0.8f, other_pts);
  int wrong_no_ratio = 0;
  for (const auto& m : stripes_no_ratio) wrong_no_ratio += errorOf(s, m) > 1.0 ? 1 : 0;
  std::printf(
      "[ figures  ] stripes (fronto-parallel): %zu points, matched %zu with ratio 0.8, "
      "%zu with ratio 1 (%d wrong); textured: %zu of %zu\n",
      stripe_pts.size(), stripes_default.size(), stripes_no_ratio.size(), wrong_no_ratio,
      others.size(), other_pts.size());
  EXPECT_EQ(stripes_default.size(), 0u) << "ambiguous stripes must fail the ratio test";
  EXPECT_GT(stripes_no_ratio.size(), stripe_pts.size() / 2)
      << "without the ratio test the stripes pass ZNCC (the test scene is really ambiguous)";
  EXPECT_GT(others.size(), other_pts.size() * 8 / 10);
  for (const auto& m : others) EXPECT_LT(errorOf(s, m), 1.0);
}

// FINDING (design weakness, not a coding slip): on stripes seen on a slanted plane (period
// 8 px in the left image, 7.76 px in the right) the peaks at d and d +- 8 no longer tie: the
// integer disparities sample each peak at a different sub-pixel phase, and the ratio test on
// c = 1 - zncc (specified in stereo_point_matcher.hpp, step 1) compares these tiny residuals
// (c ~ 1e-3), so one of the periodic peaks wins by a large ratio. Measured: 52 of the 70
// stripe points pass the row search (ratio 0.8), mostly at a wrong period (error ~ 8 px); the
// continuity check and recovery leave 16 in the output, 15 of them wrong.
// Disabled until the ratio test compares something robust to the sampling phase (e.g. the
// parabola-interpolated peak heights, or a floor on c such as max(c, 0.02)).
TEST(StereoPointMatcher, NoWrongMatchesOnSlantedStripes) {
  Scene s;
  s.box = false;
  s.stripes = true;  // s.pb = 0.03: slanted
  const ImageU8 left = s.left(), right = s.right();
  const auto pts = stripePoints(s);
  StereoPointMatcher matcher(defaultParams());
  std::vector<StereoMatch> out;
  StereoMatchStats st;
  ASSERT_TRUE(matcher.process(left.cview(), right.cview(), pts, {}, out, st).isOk());
  int wrong = 0;
  for (const auto& m : out) wrong += errorOf(s, m) > 1.0 ? 1 : 0;
  std::printf("[ figures  ] slanted stripes: %zu points, row matched %d, output %zu, wrong %d\n",
              pts.size(), st.row_matched, out.size(), wrong);
  EXPECT_EQ(wrong, 0);
}

// Plants wrong matches: for chosen points the true right patch is overwritten by another

// The refined sub-pixel disparity against the parabola on the same matches: no pull towards
// integers (mean error per fractional part) and a smaller typical error on the slanted plane.
TEST(StereoPointMatcher, RefinedSubPixelHasNoPullTowardsIntegers) {
  const Rendered& r = boxScene();
  const auto pts = randomPixels(800, r.scene.w, r.scene.h, 321);
  auto run = [&](SubpixelMethod method, std::vector<double>& bin_bias, double& med) {
    StereoMatchParams p = defaultParams();
    p.subpixel = method;
    StereoPointMatcher matcher(p);
    std::vector<StereoMatch> out;
    StereoMatchStats st;
    ASSERT_TRUE(matcher.process(r.left.cview(), r.right.cview(), pts, {}, out, st).isOk());
    std::vector<double> sum(5, 0.0), err;
    std::vector<int> n(5, 0);
    for (const StereoMatch& m : out) {
      if (r.scene.occluded(static_cast<int>(m.u_px), static_cast<int>(m.v_px))) continue;
      const double t = r.scene.truth(static_cast<int>(m.u_px), static_cast<int>(m.v_px));
      const double e = m.d_px - t;
      if (std::abs(e) > 1.0) continue;  // gross errors are another test's business
      const int b = std::min(4, static_cast<int>((t - std::floor(t)) * 5.0));
      sum[static_cast<std::size_t>(b)] += e;
      ++n[static_cast<std::size_t>(b)];
      err.push_back(std::abs(e));
    }
    bin_bias.clear();
    for (int b = 0; b < 5; ++b)
      if (n[static_cast<std::size_t>(b)] > 20)
        bin_bias.push_back(sum[static_cast<std::size_t>(b)] / n[static_cast<std::size_t>(b)]);
    med = percentile(err, 0.5);
    if (method == SubpixelMethod::kRefine) {
      EXPECT_GT(st.refined, st.matched * 9 / 10) << "the refinement converges on most matches";
    } else {
      EXPECT_EQ(st.refined, 0);
    }
  };
  std::vector<double> bias_p, bias_r;
  double med_p = 0, med_r = 0;
  run(SubpixelMethod::kParabola, bias_p, med_p);
  run(SubpixelMethod::kRefine, bias_r, med_r);
  ASSERT_EQ(bias_p.size(), 5u);
  ASSERT_EQ(bias_r.size(), 5u);
  double worst_p = 0, worst_r = 0;
  for (int b = 0; b < 5; ++b) {
    worst_p = std::max(worst_p, std::abs(bias_p[static_cast<std::size_t>(b)]));
    worst_r = std::max(worst_r, std::abs(bias_r[static_cast<std::size_t>(b)]));
  }
  std::printf(
      "[ figures  ] parabola: worst bin bias %.4f px, median |error| %.4f px; refined: "
      "%.4f px, %.4f px\n",
      worst_p, med_p, worst_r, med_r);
  EXPECT_LT(worst_r, 0.5 * worst_p);
  EXPECT_LT(med_r, med_p);
}

}  // namespace
}  // namespace svslam
