// Stereo point matcher, after the row search: seed 002's continuity check and recovery, the
// dense prior, sigma_d, parameters and bad input; checked against the rendered scene of
// stereo_point_matcher_scene.hpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "features/stereo_point_matcher.hpp"
#include "stereo_point_matcher_scene.hpp"

namespace svslam {
namespace {

using namespace stereo_scene;  // NOLINT: the shared test scene

struct Planted {
  ImageU8 right;
  std::vector<Eigen::Vector2f> pts;
  std::set<int> planted;  // indices into pts
};

Planted plantWrongMatches(const Rendered& r) {
  Planted out;
  const Scene& s = r.scene;
  out.right = s.right();
  // A grid of points on the plane, left of the box, 16 px apart.
  for (int y = 20; y < 220; y += 16)
    for (int x = 80; x < 170; x += 16) out.pts.emplace_back(x, y);
  Texture other(777);
  for (std::size_t i = 0; i < out.pts.size(); i += 9) {
    const int x = static_cast<int>(out.pts[i].x()), y = static_cast<int>(out.pts[i].y());
    if (s.occluded(x, y) || s.inBox(x, y)) continue;
    const int d_true = static_cast<int>(std::lround(s.truth(x, y)));
    const int d_wrong = d_true + 24;
    // Overwrite the true match region (wider than the patch: the sub-pixel truth) first.
    for (int dy = -5; dy <= 5; ++dy)
      for (int dx = -6; dx <= 6; ++dx)
        out.right(x - d_true + dx, y + dy) = toU8(other(dx * 1.0 + x, dy + y));
    for (int dy = -5; dy <= 5; ++dy)
      for (int dx = -5; dx <= 5; ++dx) out.right(x - d_wrong + dx, y + dy) = r.left(x + dx, y + dy);
    out.planted.insert(static_cast<int>(i));
  }
  return out;
}

TEST(StereoPointMatcher, ContinuityCheckRejectsPlantedWrongMatches) {
  const Rendered& r = boxScene();
  const Planted pl = plantWrongMatches(r);
  ASSERT_GE(pl.planted.size(), 5u);
  StereoMatchParams p = defaultParams();
  p.recovery = false;
  std::vector<StereoMatch> with, without;
  StereoMatchStats st_with, st_without;
  {
    StereoPointMatcher m(p);
    ASSERT_TRUE(m.process(r.left.cview(), pl.right.cview(), pl.pts, {}, with, st_with).isOk());
  }
  {
    p.continuity_check = false;
    StereoPointMatcher m(p);
    ASSERT_TRUE(
        m.process(r.left.cview(), pl.right.cview(), pl.pts, {}, without, st_without).isOk());
  }
  // Without the check the planted points are matched at the wrong disparity (the row search is
  // really fooled) ...
  int fooled = 0;
  for (const auto& m : without)
    if (pl.planted.count(m.index)) {
      EXPECT_GT(errorOf(r.scene, m), 20.0);
      ++fooled;
    }
  EXPECT_EQ(fooled, static_cast<int>(pl.planted.size()));
  EXPECT_EQ(st_without.continuity_rejected, 0);
  // ... and with it every planted match is gone, and only its neighbours may go with it.
  for (const auto& m : with) {
    EXPECT_EQ(pl.planted.count(m.index), 0u) << "planted wrong match " << m.index << " kept";
    EXPECT_LT(errorOf(r.scene, m), 1.0);
  }
  std::printf("[ figures  ] continuity: planted %zu, row matched %d, rejected %d, kept %zu\n",
              pl.planted.size(), st_with.row_matched, st_with.continuity_rejected, with.size());
  EXPECT_EQ(st_with.row_matched, st_without.row_matched);
  EXPECT_GE(st_with.continuity_rejected, static_cast<int>(pl.planted.size()));
  EXPECT_LE(st_with.continuity_rejected, 4 * static_cast<int>(pl.planted.size()))
      << "only the planted points and points next to them";
  EXPECT_EQ(st_with.continuity_rejected + st_with.matched, st_with.row_matched);
}

// The rule of seed 002 eq. 10 itself on a hand-made layout: two clusters of 4 plane points
// (disparity ~ 25 .. 30 px) all pass; a box point (48 px) whose 3 nearest neighbours are plane
// points differs from all of them by more than 10 px and is rejected, and counted.
TEST(StereoPointMatcher, ContinuityRuleOnFewPoints) {
  const Rendered& r = boxScene();
  // Two far-apart clusters on the plane (4 points each, 12 px apart) and one point on the box
  // whose 3 nearest neighbours are all in the lower cluster (x 100..112, y 200..212).
  std::vector<Eigen::Vector2f> pts = {{100, 200}, {112, 200}, {100, 212}, {112, 212},
                                      {40, 40},   {52, 40},   {40, 52},   {52, 52}};
  StereoMatchParams p = defaultParams();
  p.recovery = false;
  StereoPointMatcher m(p);
  std::vector<StereoMatch> out;
  StereoMatchStats st;
  ASSERT_TRUE(m.process(r.left.cview(), r.right.cview(), pts, {}, out, st).isOk());
  EXPECT_EQ(st.row_matched, 8);
  EXPECT_EQ(st.continuity_rejected, 0);
  pts.emplace_back(200, 120);  // on the box, disparity 48 vs ~27 on the plane
  ASSERT_TRUE(m.process(r.left.cview(), r.right.cview(), pts, {}, out, st).isOk());
  EXPECT_EQ(st.row_matched, 9);
  // Only the box point goes: each plane point's 3 nearest neighbours are in its own cluster.
  EXPECT_EQ(st.continuity_rejected, 1);
  for (const auto& mm : out) EXPECT_NE(mm.index, 8);
  // A threshold above the jump keeps it.
  p.continuity_threshold_px = 25.0f;
  StereoPointMatcher loose(p);
  ASSERT_TRUE(loose.process(r.left.cview(), r.right.cview(), pts, {}, out, st).isOk());
  EXPECT_EQ(st.continuity_rejected, 0);
  EXPECT_EQ(st.matched, 9);
}

TEST(StereoPointMatcher, RecoveryRestoresOnlyCorrectMatches) {
  const Rendered& r = boxScene();
  // Dense random points: near the box edges continuity rejects points on both sides.
  const auto pts = randomPixels(1500, r.scene.w, r.scene.h, 321);
  StereoMatchParams p = defaultParams();
  std::vector<StereoMatch> on, off;
  StereoMatchStats st_on, st_off;
  {
    StereoPointMatcher m(p);
    ASSERT_TRUE(m.process(r.left.cview(), r.right.cview(), pts, {}, on, st_on).isOk());
  }
  {
    p.recovery = false;
    StereoPointMatcher m(p);
    ASSERT_TRUE(m.process(r.left.cview(), r.right.cview(), pts, {}, off, st_off).isOk());
  }
  std::map<int, StereoMatch> on_by_index;
  for (const auto& m : on) on_by_index[m.index] = m;
  for (const auto& m : off) {
    ASSERT_TRUE(on_by_index.count(m.index)) << "a kept match vanished with recovery on";
    EXPECT_EQ(on_by_index[m.index].d_px, m.d_px);
    EXPECT_FALSE(on_by_index[m.index].recovered);
  }
  int recovered = 0;
  double worst = 0;
  for (const auto& m : on)
    if (m.recovered) {
      ++recovered;
      worst = std::max(worst, errorOf(r.scene, m));
      EXPECT_LT(errorOf(r.scene, m), 1.0) << "recovered match " << m.index << " is wrong";
    }
  std::printf(
      "[ figures  ] recovery: row %d rejected %d recovered %d (worst error %.3f px), "
      "matched on %d / off %d\n",
      st_on.row_matched, st_on.continuity_rejected, st_on.recovered, worst, st_on.matched,
      st_off.matched);
  EXPECT_EQ(st_off.recovered, 0);
  EXPECT_EQ(st_on.recovered, recovered);
  EXPECT_EQ(st_on.continuity_rejected, st_off.continuity_rejected);
  EXPECT_GT(recovered, 0);
  EXPECT_LT(recovered, st_on.continuity_rejected) << "partly recovered";
  EXPECT_EQ(st_on.matched, st_off.matched + recovered);
}

// With planted wrong matches, recovery brings back the correct neighbours that the check took
// with them, never the planted points (their true location is destroyed).
TEST(StereoPointMatcher, RecoveryAfterPlantedWrongMatches) {
  const Rendered& r = boxScene();
  const Planted pl = plantWrongMatches(r);
  StereoMatchParams p = defaultParams();
  StereoPointMatcher m(p);
  std::vector<StereoMatch> out;
  StereoMatchStats st;
  ASSERT_TRUE(m.process(r.left.cview(), pl.right.cview(), pl.pts, {}, out, st).isOk());
  for (const auto& mm : out) {
    EXPECT_EQ(pl.planted.count(mm.index), 0u);
    EXPECT_LT(errorOf(r.scene, mm), 1.0);
  }
  std::printf("[ figures  ] planted + recovery: rejected %d recovered %d\n", st.continuity_rejected,
              st.recovered);
  EXPECT_GT(st.recovered, 0);
  const int collateral = st.continuity_rejected - static_cast<int>(pl.planted.size());
  EXPECT_GT(collateral, 0);
  EXPECT_GE(st.recovered, collateral / 3) << "correct neighbours of planted points recovered";
  EXPECT_EQ(st.matched, st.row_matched - st.continuity_rejected + st.recovered);
}

TEST(StereoPointMatcher, DensePriorNarrowsTheSearch) {
  const Rendered& r = boxScene();
  const Scene& s = r.scene;
  const auto pts = randomPixels(500, s.w, s.h, 99);
  StereoMatchParams p = defaultParams();
  p.continuity_check = false;  // compare the row search alone
  StereoPointMatcher m(p);
  std::vector<StereoMatch> free_out, truth_out, far_out, nan_out;
  StereoMatchStats st;
  ASSERT_TRUE(m.process(r.left.cview(), r.right.cview(), pts, {}, free_out, st).isOk());
  ImageF32 prior(s.w, s.h), far(s.w, s.h), unknown(s.w, s.h);
  for (int y = 0; y < s.h; ++y)
    for (int x = 0; x < s.w; ++x) {
      prior(x, y) = static_cast<float>(s.truth(x, y));
      far(x, y) = static_cast<float>(s.truth(x, y) + 15.0);
      unknown(x, y) = (x + y) % 2 ? NAN : INFINITY;
    }
  ASSERT_TRUE(m.process(r.left.cview(), r.right.cview(), pts, prior.cview(), truth_out, st).isOk());
  ASSERT_TRUE(m.process(r.left.cview(), r.right.cview(), pts, far.cview(), far_out, st).isOk());
  EXPECT_EQ(st.candidates,
            static_cast<int>(std::count_if(pts.begin(), pts.end(), [&](const auto& q) {
              return q.x() >= 4 && q.y() >= 4 && q.x() < s.w - 4 && q.y() < s.h - 4;
            })));
  ASSERT_TRUE(m.process(r.left.cview(), r.right.cview(), pts, unknown.cview(), nan_out, st).isOk());
  std::printf("[ figures  ] prior: free %zu, prior at truth %zu, prior +15 px %zu\n",
              free_out.size(), truth_out.size(), far_out.size());
  // Prior at the truth: the same disparities wherever the free search matched correctly.
  std::map<int, float> prior_d;
  for (const auto& mm : truth_out) {
    prior_d[mm.index] = mm.d_px;
    EXPECT_LT(errorOf(s, mm), 1.0);
  }
  int same = 0, correct_free = 0;
  for (const auto& mm : free_out) {
    if (errorOf(s, mm) > 1.0) continue;
    ++correct_free;
    auto it = prior_d.find(mm.index);
    if (it != prior_d.end() && it->second == mm.d_px) ++same;
  }
  EXPECT_EQ(same, correct_free);
  EXPECT_GE(truth_out.size(), free_out.size() * 98 / 100);
  // Prior far from the truth: nothing correlates in the narrowed window.
  EXPECT_EQ(far_out.size(), 0u);
  // Unknown prior (NaN / +inf) everywhere: the full search.
  ASSERT_EQ(nan_out.size(), free_out.size());
  for (std::size_t k = 0; k < nan_out.size(); ++k) {
    EXPECT_EQ(nan_out[k].index, free_out[k].index);
    EXPECT_EQ(nan_out[k].d_px, free_out[k].d_px);
  }
}

TEST(StereoPointMatcher, BadParamsNameTheField) {
  struct Case {
    std::string field;
    void (*set)(StereoMatchParams&);
  };
  const std::vector<Case> cases = {
      {"patch_half_px", [](StereoMatchParams& p) { p.patch_half_px = 0; }},
      {"patch_half_px", [](StereoMatchParams& p) { p.patch_half_px = 16; }},
      {"min_disp_px", [](StereoMatchParams& p) { p.min_disp_px = -1; }},
      {"max_disp_px", [](StereoMatchParams& p) { p.max_disp_px = p.min_disp_px; }},
      {"min_zncc", [](StereoMatchParams& p) { p.min_zncc = 1.5f; }},
      {"min_zncc", [](StereoMatchParams& p) { p.min_zncc = NAN; }},
      {"ratio", [](StereoMatchParams& p) { p.ratio = 0.0f; }},
      {"ratio", [](StereoMatchParams& p) { p.ratio = 1.01f; }},
      {"prior_radius_px", [](StereoMatchParams& p) { p.prior_radius_px = 0; }},
      {"continuity_threshold_px", [](StereoMatchParams& p) { p.continuity_threshold_px = 0; }},
      {"continuity_threshold_px", [](StereoMatchParams& p) { p.continuity_threshold_px = NAN; }},
      {"recovery_dist_th_px", [](StereoMatchParams& p) { p.recovery_dist_th_px = -1; }},
      {"recovery_margin_px", [](StereoMatchParams& p) { p.recovery_margin_px = -1; }},
      {"sigma_d_px", [](StereoMatchParams& p) { p.sigma_d_px = 0; }},
      {"sigma_d_px", [](StereoMatchParams& p) { p.sigma_d_px = INFINITY; }},
      {"min_sigma_d_px", [](StereoMatchParams& p) { p.min_sigma_d_px = -0.1f; }},
      {"min_sigma_d_px", [](StereoMatchParams& p) { p.min_sigma_d_px = NAN; }},
      {"sigma_mode", [](StereoMatchParams& p) { p.sigma_mode = static_cast<StereoSigmaMode>(7); }},
      {"sigma_model", [](StereoMatchParams& p) { p.sigma_model.sigma_px.back() = 5.0f; }},
      {"sigma_model", [](StereoMatchParams& p) { p.sigma_model = SigmaModel{}; }},
  };
  EXPECT_TRUE(StereoMatchParams{}.validate().isOk());
  const Rendered& r = boxScene();
  for (const auto& c : cases) {
    StereoMatchParams p;
    c.set(p);
    const Status s = p.validate();
    ASSERT_FALSE(s.isOk()) << c.field;
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
    EXPECT_NE(s.message().find(c.field), std::string::npos) << s.message();
    StereoPointMatcher m(p);
    EXPECT_FALSE(m.initStatus().isOk());
    std::vector<StereoMatch> out(3);
    StereoMatchStats st;
    EXPECT_FALSE(m.process(r.left.cview(), r.right.cview(), {{100, 100}}, {}, out, st).isOk());
    EXPECT_TRUE(out.empty());
  }
}

// sigma_d of a match: the calibrated table of its peak curvature (sharper peak, smaller sigma),
// floored by min_sigma_d_px; in fixed mode sigma_d_px for every match. The disparities do not
// depend on the mode.
TEST(StereoPointMatcher, SigmaFromPeakCurvatureOrFixed) {
  const Rendered& r = boxScene();
  const auto pts = randomPixels(400, r.scene.w, r.scene.h, 321);
  auto run = [&](const StereoMatchParams& p) {
    StereoPointMatcher matcher(p);
    EXPECT_TRUE(matcher.initStatus().isOk());
    std::vector<StereoMatch> out;
    StereoMatchStats st;
    EXPECT_TRUE(matcher.process(r.left.cview(), r.right.cview(), pts, {}, out, st).isOk());
    return out;
  };
  StereoMatchParams curv_p = defaultParams();
  curv_p.sigma_mode = StereoSigmaMode::kCurvature;
  const auto curv = run(curv_p);
  ASSERT_GT(curv.size(), 100u);
  const auto fixed = run(defaultParams());  // kFixed is the default
  EXPECT_EQ(defaultParams().sigma_mode, StereoSigmaMode::kFixed);
  StereoMatchParams floor_p = curv_p;
  floor_p.min_sigma_d_px = 0.4f;
  const auto floored = run(floor_p);
  ASSERT_EQ(curv.size(), fixed.size());
  ASSERT_EQ(curv.size(), floored.size());
  const SigmaModel model = SigmaModel::defaultZnccPoints();
  for (std::size_t k = 0; k < curv.size(); ++k) {
    EXPECT_EQ(curv[k].d_px, fixed[k].d_px);
    EXPECT_EQ(curv[k].curvature, fixed[k].curvature);
    // kappa = 2 s(d) - s(d-1) - s(d+1) >= 0 at an accepted maximum, at most 4 (ZNCC in [-1, 1]).
    EXPECT_GE(curv[k].curvature, 0.0f);
    EXPECT_LE(curv[k].curvature, 4.0f);
    EXPECT_FLOAT_EQ(curv[k].sigma_d_px, model.sigmaFor(curv[k].curvature));
    EXPECT_FLOAT_EQ(fixed[k].sigma_d_px, 0.3f);
    EXPECT_FLOAT_EQ(floored[k].sigma_d_px, std::max(0.4f, curv[k].sigma_d_px));
    for (std::size_t j = 0; j < k; ++j)
      if (curv[j].curvature > curv[k].curvature) {
        EXPECT_LE(curv[j].sigma_d_px, curv[k].sigma_d_px);
      }
  }
}

TEST(StereoPointMatcher, SizeMismatchIsAnError) {
  const Rendered& r = boxScene();
  StereoPointMatcher m(defaultParams());
  ImageU8 small(100, 80);
  small.fill(7);
  std::vector<StereoMatch> out;
  StereoMatchStats st;
  const std::vector<Eigen::Vector2f> pts{{50, 50}};
  EXPECT_EQ(m.process(r.left.cview(), small.cview(), pts, {}, out, st).code(),
            StatusCode::kInvalidArgument);
  EXPECT_FALSE(m.process(small.cview(), r.right.cview(), pts, {}, out, st).isOk());
  EXPECT_FALSE(m.process({}, {}, pts, {}, out, st).isOk());
  ImageF32 prior(100, 80);
  EXPECT_FALSE(m.process(r.left.cview(), r.right.cview(), pts, prior.cview(), out, st).isOk());
}

TEST(StereoPointMatcher, BorderPointsAreSkipped) {
  const Rendered& r = boxScene();
  const int w = r.scene.w, h = r.scene.h;
  const std::vector<Eigen::Vector2f> pts = {{0, 0},          {-3, 50},        {w - 1.0f, h - 1.0f},
                                            {w + 5.0f, 10},  {3.4f, 100},     {100, 3.49f},
                                            {w - 4.6f, 100}, {100, h - 4.6f}, {4, 100},
                                            {12, 120},       {1e9f, 1e9f},    {w - 4.0f, 100}};
  StereoPointMatcher m(defaultParams());
  std::vector<StereoMatch> out;
  StereoMatchStats st;
  ASSERT_TRUE(m.process(r.left.cview(), r.right.cview(), pts, {}, out, st).isOk());
  // Inside (9x9 patch, positions rounded): (4, 100), (12, 120), (w - 5, 100), (100, h - 5).
  // (4, 100) and (12, 120) have too small a disparity range to reach the truth (~ 23 px).
  EXPECT_EQ(st.candidates, 4);
  for (const auto& mm : out) EXPECT_TRUE(mm.index == 6 || mm.index == 7) << mm.index;
}

}  // namespace
}  // namespace svslam
