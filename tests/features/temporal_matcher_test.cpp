// Temporal matcher on a synthetic scene with exact ground truth: two textured planes (a tilted
// background wall and a closer fronto-parallel panel) rendered by ray casting from two known
// camera poses; the stereo points of both frames come from the true geometry plus seeded noise
// drawn from their stated covariance.
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

namespace svslam {
namespace {

// Continuous band-limited texture on a plane (metres): a sum of random plane waves.
class Texture {
 public:
  Texture(unsigned seed, double lambda_min_m, double lambda_max_m, int k = 24) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u01(0, 1);
    for (int i = 0; i < k; ++i) {
      const double th = 2 * M_PI * u01(rng);
      const double lambda = lambda_min_m * std::pow(lambda_max_m / lambda_min_m, u01(rng));
      const double w = 2 * M_PI / lambda;
      waves_.push_back({w * std::cos(th), w * std::sin(th), 2 * M_PI * u01(rng)});
    }
    amp_ = 55.0 / std::sqrt(0.5 * k);
  }
  double operator()(double x, double y) const {
    double s = 0;
    for (const auto& w : waves_) s += std::sin(w[0] * x + w[1] * y + w[2]);
    return 128.0 + amp_ * s;
  }

 private:
  std::vector<std::array<double, 3>> waves_;
  double amp_ = 1;
};

// World frame = previous left camera frame. Background: the plane -0.2 x + 0.1 y + z = 4
// (z ~ 3.4 .. 4.6 m in view); panel: z = 2.5 m for x in [-0.9, -0.1], y in [-0.6, 0.5].
struct World {
  PinholeCamera cam{400.0, 400.0, 160.0, 120.0, 320, 240};
  Texture bg{5, 0.08, 0.5}, panel{6, 0.06, 0.3};

  // Nearest surface point along origin + t dir (t > 0), world frame; false when none.
  bool cast(const Eigen::Vector3d& o, const Eigen::Vector3d& dir, Eigen::Vector3d& X,
            int& surface) const {
    double best = HUGE_VAL;
    if (std::abs(dir.z()) > 1e-12) {
      const double t = (2.5 - o.z()) / dir.z();
      const Eigen::Vector3d q = o + t * dir;
      if (t > 0 && q.x() >= -0.9 && q.x() <= -0.1 && q.y() >= -0.6 && q.y() <= 0.5) {
        best = t;
        X = q;
        surface = 1;
      }
    }
    const Eigen::Vector3d n(-0.2, 0.1, 1.0);
    const double den = n.dot(dir);
    if (std::abs(den) > 1e-12) {
      const double t = (4.0 - n.dot(o)) / den;
      if (t > 0 && t < best) {
        best = t;
        X = o + t * dir;
        surface = 0;
      }
    }
    return best < HUGE_VAL;
  }
  // Ray of pixel (u, v) of a camera with pose T_cam_world, in the world frame.
  bool castPixel(const Eigen::Isometry3d& T_cam_world, double u, double v, Eigen::Vector3d& X,
                 int& surface) const {
    const Eigen::Isometry3d T_world_cam = T_cam_world.inverse();
    const Eigen::Vector3d d_cam((u - cam.cx_px) / cam.fx_px, (v - cam.cy_px) / cam.fy_px, 1.0);
    return cast(T_world_cam.translation(), T_world_cam.linear() * d_cam, X, surface);
  }
  double shade(const Eigen::Vector3d& X, int surface) const {
    return surface == 1 ? panel(X.x(), X.y()) : bg(X.x(), X.y());
  }
  ImageU8 render(const Eigen::Isometry3d& T_cam_world) const {
    ImageU8 img(cam.width, cam.height);
    for (int v = 0; v < cam.height; ++v)
      for (int u = 0; u < cam.width; ++u) {
        Eigen::Vector3d X;
        int s = 0;
        const double g = castPixel(T_cam_world, u, v, X, s) ? shade(X, s) : 0.0;
        img(u, v) = static_cast<std::uint8_t>(std::clamp(std::lround(g), 0L, 255L));
      }
    return img;
  }
};

// Stereo-like covariance of a point p_cam (b = 0.3 m, sigma 0.3 px in u, v and d): lateral
// sigma z s / f, along the ray z^2 s / (f b).
Eigen::Matrix3d stereoCov(const PinholeCamera& cam, const Eigen::Vector3d& p_cam,
                          Eigen::Matrix3d& L) {
  const double z = p_cam.z(), s = 0.3, b = 0.3;
  const double sl = z * s / cam.fx_px, sz = z * z * s / (cam.fx_px * b);
  const Eigen::Vector3d r = p_cam.normalized();
  Eigen::Vector3d a = r.cross(Eigen::Vector3d::UnitX()).normalized();
  const Eigen::Vector3d c = r.cross(a);
  Eigen::Matrix3d B;
  B << a, c, r;
  L = B * Eigen::Vector3d(sl, sl, sz).asDiagonal();
  return L * L.transpose();
}

TrackPoint makePoint(const PinholeCamera& cam, double u, double v, const Eigen::Vector3d& p_true,
                     std::mt19937& rng) {
  std::normal_distribution<double> n01(0, 1);
  TrackPoint p;
  p.u_px = static_cast<float>(u);
  p.v_px = static_cast<float>(v);
  Eigen::Matrix3d L;
  p.cov = stereoCov(cam, p_true, L);
  p.p_cam = p_true + L * Eigen::Vector3d(n01(rng), n01(rng), n01(rng));
  return p;
}

bool patchIn(const PinholeCamera& cam, double u, double v, int h) {
  const long x = std::lround(u), y = std::lround(v);
  return x - h >= 0 && y - h >= 0 && x + h < cam.width && y + h < cam.height;
}

struct Frames {
  World world;
  Eigen::Isometry3d T_cur_prev = Eigen::Isometry3d::Identity();
  ImageU8 prev_img, cur_img;
  std::vector<TrackPoint> prev, cur;
  std::vector<int> truth;  // current index of each previous point, -1 when it has none
  int visible = 0;         // previous points with a counterpart, both patches inside (h = 5)
};

const Frames& frames() {
  static const Frames f = [] {
    Frames out;
    const World& w = out.world;
    const PinholeCamera& cam = w.cam;
    // ~3.2 degrees about a skewed axis, 0.3 m of translation.
    out.T_cur_prev.linear() =
        Eigen::AngleAxisd(0.056, Eigen::Vector3d(0.3, 1.0, 0.2).normalized()).toRotationMatrix();
    out.T_cur_prev.translation() = Eigen::Vector3d(0.15, -0.05, 0.25);
    out.prev_img = w.render(Eigen::Isometry3d::Identity());
    out.cur_img = w.render(out.T_cur_prev);
    std::mt19937 rng(2024);
    std::uniform_int_distribution<int> ux(0, cam.width - 1), uy(0, cam.height - 1);
    std::vector<Eigen::Vector2d> used;
    std::vector<TrackPoint> cur_true;  // before shuffling
    std::vector<int> cur_of_prev;
    while (out.prev.size() < 420) {
      const int u = ux(rng), v = uy(rng);
      bool near = false;
      for (const auto& q : used) near = near || (q - Eigen::Vector2d(u, v)).norm() < 5.0;
      if (near) continue;
      used.emplace_back(u, v);
      Eigen::Vector3d X;
      int s = 0;
      if (!w.castPixel(Eigen::Isometry3d::Identity(), u, v, X, s)) continue;
      out.prev.push_back(makePoint(cam, u, v, X, rng));
      // Counterpart: the projection into the current image when not occluded there.
      const Eigen::Vector3d Xc = out.T_cur_prev * X;
      double uc, vc;
      int idx = -1;
      if (cam.project(Xc.x(), Xc.y(), Xc.z(), uc, vc) && uc >= 0 && vc >= 0 &&
          uc <= cam.width - 1 && vc <= cam.height - 1) {
        Eigen::Vector3d Y;
        int s2 = 0;
        if (w.castPixel(out.T_cur_prev, uc, vc, Y, s2) && (Y - X).norm() < 1e-6) {
          idx = static_cast<int>(cur_true.size());
          cur_true.push_back(makePoint(cam, uc, vc, Xc, rng));
          if (patchIn(cam, u, v, 5) && patchIn(cam, uc, vc, 5)) ++out.visible;
        }
      }
      cur_of_prev.push_back(idx);
    }
    // Points detected in the current frame only, away from the counterparts.
    const std::size_t n_true = cur_true.size();
    std::uniform_real_distribution<double> fu(0, cam.width - 1), fv(0, cam.height - 1);
    while (cur_true.size() < n_true + 80) {
      const double u = fu(rng), v = fv(rng);
      bool near = false;
      for (const auto& c : cur_true) near = near || std::hypot(c.u_px - u, c.v_px - v) < 4.0;
      if (near) continue;
      Eigen::Vector3d X;
      int s = 0;
      if (!w.castPixel(out.T_cur_prev, u, v, X, s)) continue;
      cur_true.push_back(makePoint(cam, u, v, out.T_cur_prev * X, rng));
    }
    std::vector<int> perm(cur_true.size());  // perm[old] = new
    std::iota(perm.begin(), perm.end(), 0);
    std::shuffle(perm.begin(), perm.end(), rng);
    out.cur.resize(cur_true.size());
    for (std::size_t i = 0; i < cur_true.size(); ++i)
      out.cur[static_cast<std::size_t>(perm[i])] = cur_true[i];
    for (int c : cur_of_prev) out.truth.push_back(c < 0 ? -1 : perm[static_cast<std::size_t>(c)]);
    return out;
  }();
  return f;
}

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
