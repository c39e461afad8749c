// Temporal matcher on a synthetic scene with exact ground truth (temporal_matcher_scene.hpp:
// two textured planes rendered by ray casting from two known camera poses).
#include "features/temporal_matcher.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "temporal_matcher_scene.hpp"

namespace svslam {
namespace {

using namespace temporal_scene;  // NOLINT: the shared scene

struct Outcome {
  std::vector<TemporalMatch> out;
  TemporalMatchStats st;
  int correct = 0;
};

Outcome run(const Frames& f, const std::vector<TrackPoint>& prev, const std::vector<int>& truth,
            const std::vector<TrackPoint>& cur, const Eigen::Isometry3d& pred,
            const TemporalMatchParams& p, float radius = 0.0f) {
  Outcome o;
  TemporalMatcher m(p);
  EXPECT_TRUE(m.initStatus().isOk());
  EXPECT_TRUE(m.process(f.prev_img.cview(), prev, f.cur_img.cview(), cur, pred, f.world.cam, o.out,
                        o.st, radius)
                  .isOk());
  for (const auto& mm : o.out)
    o.correct += truth[static_cast<std::size_t>(mm.prev)] == mm.cur ? 1 : 0;
  return o;
}

void expectOneToOneSorted(const std::vector<TemporalMatch>& out, std::size_t n_prev,
                          std::size_t n_cur) {
  std::set<int> cur_used;
  for (std::size_t k = 0; k < out.size(); ++k) {
    ASSERT_GE(out[k].prev, 0);
    ASSERT_LT(out[k].prev, static_cast<int>(n_prev));
    ASSERT_GE(out[k].cur, 0);
    ASSERT_LT(out[k].cur, static_cast<int>(n_cur));
    if (k > 0) {
      EXPECT_LT(out[k - 1].prev, out[k].prev) << "sorted by previous index, each once";
    }
    EXPECT_TRUE(cur_used.insert(out[k].cur).second)
        << "current point " << out[k].cur << " used twice";
  }
}

TEST(TemporalMatcher, TrueMotionMatchesVisiblePointsCorrectly) {
  const Frames& f = frames();
  ASSERT_GT(f.visible, 250);
  const Outcome o = run(f, f.prev, f.truth, f.cur, f.T_cur_prev, TemporalMatchParams{});
  std::printf(
      "[ figures  ] temporal, true prediction: prev %zu cur %zu visible %d | predicted %d "
      "signal %d geometry_rejected %d matched %d correct %d (%.1f %% of visible, %.2f %% "
      "correct)\n",
      f.prev.size(), f.cur.size(), f.visible, o.st.predicted, o.st.signal_matched,
      o.st.geometry_rejected, o.st.matched, o.correct, 100.0 * o.correct / f.visible,
      100.0 * o.correct / std::max<std::size_t>(1, o.out.size()));
  expectOneToOneSorted(o.out, f.prev.size(), f.cur.size());
  EXPECT_EQ(o.st.matched, static_cast<int>(o.out.size()));
  EXPECT_EQ(o.st.signal_matched - o.st.geometry_rejected, o.st.matched);
  EXPECT_GE(o.st.predicted, f.visible);
  EXPECT_GE(o.correct, 0.9 * f.visible);
  EXPECT_GE(o.correct, 0.99 * static_cast<double>(o.out.size()));
  for (const auto& mm : o.out) EXPECT_GE(mm.score, 0.8f);
  // With correct data the geometric check removes next to nothing.
  EXPECT_LE(o.st.geometry_rejected, o.st.signal_matched / 50);
}

TEST(TemporalMatcher, PredictionAndRadiusMatter) {
  const Frames& f = frames();
  TemporalMatchParams small;
  small.search_radius_px = 5.0f;
  const Outcome truth_small = run(f, f.prev, f.truth, f.cur, f.T_cur_prev, small);
  const Outcome ident_small = run(f, f.prev, f.truth, f.cur, Eigen::Isometry3d::Identity(), small);
  // The override radius (after a tracking loss) with no motion prediction.
  const Outcome ident_wide =
      run(f, f.prev, f.truth, f.cur, Eigen::Isometry3d::Identity(), TemporalMatchParams{}, 90.0f);
  std::printf(
      "[ figures  ] temporal: radius 5 true prediction %d (%d correct), identity %d; "
      "identity + radius 90 %d (%d correct)\n",
      truth_small.st.matched, truth_small.correct, ident_small.st.matched, ident_wide.st.matched,
      ident_wide.correct);
  EXPECT_GE(truth_small.correct, 0.9 * f.visible) << "a small radius is enough with the truth";
  EXPECT_LT(ident_small.st.matched, truth_small.st.matched / 5);
  EXPECT_GT(ident_wide.correct, ident_small.correct);
  EXPECT_GE(ident_wide.correct, 0.99 * static_cast<double>(ident_wide.out.size()));
  expectOneToOneSorted(ident_wide.out, f.prev.size(), f.cur.size());
}

TEST(TemporalMatcher, GeometricCheckRemovesInconsistent3D) {
  const Frames& f = frames();
  const Outcome base = run(f, f.prev, f.truth, f.cur, f.T_cur_prev, TemporalMatchParams{});
  // Swap the 3D points (and covariances) of pairs of correctly matched current points far
  // apart in 3D; images and positions stay, so the signal still matches them.
  std::vector<TemporalMatch> correct;
  for (const auto& mm : base.out)
    if (f.truth[static_cast<std::size_t>(mm.prev)] == mm.cur) correct.push_back(mm);
  std::mt19937 rng(77);
  std::shuffle(correct.begin(), correct.end(), rng);
  std::vector<TrackPoint> cur = f.cur;
  std::set<int> swapped_prev;
  std::vector<Eigen::Vector2f> chosen;
  auto farFromChosen = [&](const TrackPoint& p) {
    for (const auto& c : chosen)
      if (std::hypot(c.x() - p.u_px, c.y() - p.v_px) < 40.0f) return false;
    return true;
  };
  for (std::size_t a = 0; a < correct.size() && swapped_prev.size() < 16; ++a) {
    const TrackPoint& pa = f.cur[static_cast<std::size_t>(correct[a].cur)];
    if (swapped_prev.count(correct[a].prev) || !farFromChosen(pa)) continue;
    for (std::size_t b = a + 1; b < correct.size(); ++b) {
      const TrackPoint& pb = f.cur[static_cast<std::size_t>(correct[b].cur)];
      if (swapped_prev.count(correct[b].prev) || (pa.p_cam - pb.p_cam).norm() < 0.6) continue;
      chosen.emplace_back(pa.u_px, pa.v_px);
      if (!farFromChosen(pb)) {
        chosen.pop_back();
        continue;
      }
      chosen.emplace_back(pb.u_px, pb.v_px);
      auto& ca = cur[static_cast<std::size_t>(correct[a].cur)];
      auto& cb = cur[static_cast<std::size_t>(correct[b].cur)];
      std::swap(ca.p_cam, cb.p_cam);
      std::swap(ca.cov, cb.cov);
      swapped_prev.insert(correct[a].prev);
      swapped_prev.insert(correct[b].prev);
      break;
    }
  }
  ASSERT_EQ(swapped_prev.size(), 16u);
  const Outcome checked = run(f, f.prev, f.truth, cur, f.T_cur_prev, TemporalMatchParams{});
  TemporalMatchParams off;
  off.group_size = 0;
  const Outcome unchecked = run(f, f.prev, f.truth, cur, f.T_cur_prev, off);
  int swapped_kept = 0, swapped_unchecked = 0, good_kept = 0;
  for (const auto& mm : checked.out) swapped_kept += swapped_prev.count(mm.prev) ? 1 : 0;
  for (const auto& mm : unchecked.out) swapped_unchecked += swapped_prev.count(mm.prev) ? 1 : 0;
  for (const auto& mm : checked.out)
    good_kept +=
        (!swapped_prev.count(mm.prev) && f.truth[static_cast<std::size_t>(mm.prev)] == mm.cur) ? 1
                                                                                               : 0;
  const int good_before = static_cast<int>(correct.size()) - 16;
  std::printf(
      "[ figures  ] temporal, 16 swapped 3D points: signal %d geometry_rejected %d, "
      "swapped kept %d (without check %d), correct kept %d of %d\n",
      checked.st.signal_matched, checked.st.geometry_rejected, swapped_kept, swapped_unchecked,
      good_kept, good_before);
  EXPECT_EQ(swapped_unchecked, 16) << "the signal alone keeps the swapped matches";
  EXPECT_EQ(unchecked.st.geometry_rejected, 0);
  EXPECT_EQ(swapped_kept, 0);
  EXPECT_GE(checked.st.geometry_rejected, 16);
  EXPECT_GE(good_kept, 0.97 * good_before);
  expectOneToOneSorted(checked.out, f.prev.size(), cur.size());
}

TEST(TemporalMatcher, CurrentPointKeepsOnePreviousPoint) {
  const Frames& f = frames();
  const Outcome base = run(f, f.prev, f.truth, f.cur, f.T_cur_prev, TemporalMatchParams{});
  ASSERT_GT(base.out.size(), 10u);
  // Append copies of matched previous points: each copy competes with its original for the
  // same current point with the same score; exactly one of the two may be matched.
  std::vector<TrackPoint> prev = f.prev;
  std::vector<int> truth = f.truth;
  std::vector<std::pair<int, int>> pairs;
  for (std::size_t k = 0; k < base.out.size(); k += 10) {
    pairs.emplace_back(base.out[k].prev, static_cast<int>(prev.size()));
    prev.push_back(prev[static_cast<std::size_t>(base.out[k].prev)]);
    truth.push_back(truth[static_cast<std::size_t>(base.out[k].prev)]);
  }
  TemporalMatchParams p;
  p.group_size = 0;  // duplicated 3D points have zero distance: keep the check out of this test
  const Outcome o = run(f, prev, truth, f.cur, f.T_cur_prev, p);
  expectOneToOneSorted(o.out, prev.size(), f.cur.size());
  std::set<int> matched_prev;
  for (const auto& mm : o.out) matched_prev.insert(mm.prev);
  for (const auto& [a, b] : pairs)
    EXPECT_EQ(matched_prev.count(a) + matched_prev.count(b), 1u) << a << " / copy " << b;
}

TEST(TemporalMatcher, BadParamsAndInputs) {
  struct Case {
    std::string field;
    void (*set)(TemporalMatchParams&);
  };
  const std::vector<Case> cases = {
      {"patch_half_px", [](TemporalMatchParams& p) { p.patch_half_px = 0; }},
      {"patch_half_px", [](TemporalMatchParams& p) { p.patch_half_px = 16; }},
      {"search_radius_px", [](TemporalMatchParams& p) { p.search_radius_px = 0; }},
      {"search_radius_px", [](TemporalMatchParams& p) { p.search_radius_px = INFINITY; }},
      {"min_zncc", [](TemporalMatchParams& p) { p.min_zncc = -1.5f; }},
      {"min_zncc", [](TemporalMatchParams& p) { p.min_zncc = NAN; }},
      {"ratio", [](TemporalMatchParams& p) { p.ratio = 0; }},
      {"ratio", [](TemporalMatchParams& p) { p.ratio = 1.5f; }},
      {"group_size", [](TemporalMatchParams& p) { p.group_size = -1; }},
      {"group_size", [](TemporalMatchParams& p) { p.group_size = 33; }},
      {"group_n_sigma", [](TemporalMatchParams& p) { p.group_n_sigma = 0; }},
      {"group_n_sigma", [](TemporalMatchParams& p) { p.group_n_sigma = NAN; }},
      {"group_min_fraction", [](TemporalMatchParams& p) { p.group_min_fraction = -0.1; }},
      {"group_min_fraction", [](TemporalMatchParams& p) { p.group_min_fraction = 1.1; }},
  };
  EXPECT_TRUE(TemporalMatchParams{}.validate().isOk());
  const Frames& f = frames();
  for (const auto& c : cases) {
    TemporalMatchParams p;
    c.set(p);
    const Status s = p.validate();
    ASSERT_FALSE(s.isOk()) << c.field;
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
    EXPECT_NE(s.message().find(c.field), std::string::npos) << s.message();
    TemporalMatcher m(p);
    EXPECT_FALSE(m.initStatus().isOk());
    std::vector<TemporalMatch> out(2);
    TemporalMatchStats st;
    EXPECT_FALSE(m.process(f.prev_img.cview(), f.prev, f.cur_img.cview(), f.cur, f.T_cur_prev,
                           f.world.cam, out, st)
                     .isOk());
    EXPECT_TRUE(out.empty());
  }
  TemporalMatcher m(TemporalMatchParams{});
  std::vector<TemporalMatch> out;
  TemporalMatchStats st;
  ImageU8 small(100, 80);
  small.fill(1);
  EXPECT_EQ(m.process(f.prev_img.cview(), f.prev, small.cview(), f.cur, f.T_cur_prev, f.world.cam,
                      out, st)
                .code(),
            StatusCode::kInvalidArgument);
  // Empty point sets and points behind the camera: no match, no error.
  ASSERT_TRUE(m.process(f.prev_img.cview(), {}, f.cur_img.cview(), f.cur, f.T_cur_prev, f.world.cam,
                        out, st)
                  .isOk());
  EXPECT_TRUE(out.empty());
  ASSERT_TRUE(m.process(f.prev_img.cview(), f.prev, f.cur_img.cview(), {}, f.T_cur_prev,
                        f.world.cam, out, st)
                  .isOk());
  EXPECT_TRUE(out.empty());
  std::vector<TrackPoint> behind = f.prev;
  for (auto& p : behind) p.p_cam.z() = -p.p_cam.z();
  ASSERT_TRUE(m.process(f.prev_img.cview(), behind, f.cur_img.cview(), f.cur,
                        Eigen::Isometry3d::Identity(), f.world.cam, out, st)
                  .isOk());
  EXPECT_EQ(st.predicted, 0);
  EXPECT_TRUE(out.empty());
}

}  // namespace
}  // namespace svslam
