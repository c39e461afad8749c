#include "features/stereo_point_matcher.hpp"

#include <algorithm>
#include <cmath>

#include "features/patch_similarity.hpp"

namespace svslam {

Status StereoMatchParams::validate() const {
  if (patch_half_px < 1 || patch_half_px > 15)
    return Status::invalidArgument("stereo_match.patch_half_px must be in 1..15");
  if (min_disp_px < 0) return Status::invalidArgument("stereo_match.min_disp_px must be >= 0");
  if (max_disp_px <= min_disp_px)
    return Status::invalidArgument("stereo_match.max_disp_px must be > min_disp_px");
  if (!(min_zncc >= -1.0f && min_zncc <= 1.0f))
    return Status::invalidArgument("stereo_match.min_zncc must be in -1..1");
  if (!(ratio > 0.0f && ratio <= 1.0f))
    return Status::invalidArgument("stereo_match.ratio must be in (0, 1]");
  if (!(ratio_floor >= 0.0f && ratio_floor <= 1.0f))
    return Status::invalidArgument("stereo_match.ratio_floor must be in 0..1");
  if (prior_radius_px < 1)
    return Status::invalidArgument("stereo_match.prior_radius_px must be >= 1");
  if (!(continuity_threshold_px > 0.0f))
    return Status::invalidArgument("stereo_match.continuity_threshold_px must be > 0");
  if (!(recovery_dist_th_px > 0.0f))
    return Status::invalidArgument("stereo_match.recovery_dist_th_px must be > 0");
  if (recovery_margin_px < 0)
    return Status::invalidArgument("stereo_match.recovery_margin_px must be >= 0");
  if (!(sigma_d_px > 0.0f) || !std::isfinite(sigma_d_px))
    return Status::invalidArgument("stereo_match.sigma_d_px must be > 0");
  if (!(min_sigma_d_px >= 0.0f) || !std::isfinite(min_sigma_d_px))
    return Status::invalidArgument("stereo_match.min_sigma_d_px must be >= 0");
  if (sigma_mode != StereoSigmaMode::kCurvature && sigma_mode != StereoSigmaMode::kFixed)
    return Status::invalidArgument("stereo_match.sigma_mode must be curvature or fixed");
  if (Status s = sigma_model.validate(); !s)  // checked in either mode: a bad table is a bad config
    return Status::invalidArgument("stereo_match.sigma_model: " + s.message());
  if (subpixel != SubpixelMethod::kParabola && subpixel != SubpixelMethod::kRefine)
    return Status::invalidArgument("stereo_match.subpixel must be parabola or refine");
  if (Status s = refine.validate(); !s)
    return Status::invalidArgument("stereo_match." + s.message());
  return Status::ok();
}

StereoPointMatcher::StereoPointMatcher(const StereoMatchParams& params)
    : params_(params), init_status_(params.validate()) {
  scores_.reserve(1024);
  row_.reserve(1024);
  // znccRow's scratch for the widest scan (1024 disparities, patch half 15 at most).
  zncc_scratch_.sab.reserve(1024 + 1);
  zncc_scratch_.col_sum.reserve(1024 + 1 + 30);
  zncc_scratch_.col_sq.reserve(1024 + 1 + 30);
  // Per match of a frame (continuity check, recovery); grown once past this for more points.
  keep_.reserve(2048);
  rejected_.reserve(2048);
  tri_pts_.reserve(2048);
}

namespace {

// Sub-pixel offset of the maximum of a parabola through (s_minus, s0, s_plus), in [-0.5, 0.5].
float parabolaPeak(float sm, float s0, float sp) {
  const float den = sm - 2.0f * s0 + sp;
  if (!(den < 0.0f)) return 0.0f;
  return std::clamp(0.5f * (sm - sp) / den, -0.5f, 0.5f);
}

}  // namespace

void StereoPointMatcher::setPeak(ImageView<const std::uint8_t> left,
                                 ImageView<const std::uint8_t> right, int x, int y, int d, float sm,
                                 float s0, float sp, StereoMatch& m) {
  m.d_px = static_cast<float>(d) + parabolaPeak(sm, s0, sp);
  m.refined = false;
  double d_ref = 0.0;
  if (params_.subpixel == SubpixelMethod::kRefine &&
      refineDisparity(left, right, x, y, params_.patch_half_px, m.d_px, params_.refine, d_ref)) {
    m.d_px = static_cast<float>(d_ref);
    m.refined = true;
  }
  m.score = s0;
  m.curvature = std::max(0.0f, 2.0f * s0 - sm - sp);
  m.sigma_d_px = params_.sigma_mode == StereoSigmaMode::kFixed
                     ? params_.sigma_d_px
                     : std::max(params_.min_sigma_d_px, params_.sigma_model.sigmaFor(m.curvature));
}

void StereoPointMatcher::scanRow(ImageView<const std::uint8_t> left,
                                 ImageView<const std::uint8_t> right, const PatchStats& ps, int y,
                                 int d0, int d1) {
  const std::size_t n = static_cast<std::size_t>(d1 - d0 + 1);
  row_.resize(n);
  scores_.resize(n);
  znccRow(left, ps, right, ps.x - d1, y, static_cast<int>(n), row_.data(), zncc_scratch_);
  for (std::size_t k = 0; k < n; ++k) scores_[k] = row_[n - 1 - k];
}

bool StereoPointMatcher::searchRow(ImageView<const std::uint8_t> left,
                                   ImageView<const std::uint8_t> right, int x, int y, int d0,
                                   int d1, StereoMatch& m) {
  const int h = params_.patch_half_px;
  d1 = std::min(d1, x - h);  // right patch inside the image
  if (d1 < d0) return false;
  const PatchStats ps = patchStats(left, x, y, h);
  if (ps.inv_norm == 0.0) return false;
  scanRow(left, right, ps, y, d0, d1);
  int best = -1;
  for (int d = d0; d <= d1; ++d) {
    const float s = scores_[static_cast<std::size_t>(d - d0)];
    if (best < 0 || s > scores_[static_cast<std::size_t>(best)]) best = d - d0;
  }
  const float sb = scores_[static_cast<std::size_t>(best)];
  if (sb < params_.min_zncc) return false;
  // Second best: the highest other local maximum of the score curve (the flanks of the best
  // peak are not competitors, whatever their height on a smooth patch).
  float second = -1.0f;
  const int last = d1 - d0;
  for (int i = 0; i <= last; ++i) {
    if (std::abs(i - best) <= 1) continue;
    const float si = scores_[static_cast<std::size_t>(i)];
    const bool peak = (i == 0 || si >= scores_[static_cast<std::size_t>(i - 1)]) &&
                      (i == last || si >= scores_[static_cast<std::size_t>(i + 1)]);
    if (peak) second = std::max(second, si);
  }
  if (std::max(1.0f - sb, params_.ratio_floor) > params_.ratio * (1.0f - second)) return false;
  // A peak on the border of the searched range may be a slope towards a peak outside it.
  if (best == 0 || best == d1 - d0) return false;
  const float sm = scores_[static_cast<std::size_t>(best - 1)];
  const float sp = scores_[static_cast<std::size_t>(best + 1)];
  setPeak(left, right, x, y, d0 + best, sm, sb, sp, m);
  return true;
}

bool StereoPointMatcher::matchPoint(ImageView<const std::uint8_t> left,
                                    ImageView<const std::uint8_t> right, int x, int y, int d0,
                                    int d1, StereoMatch& out) {
  if (!init_status_ || left.width != right.width || left.height != right.height) return false;
  if (!patchInside(left, x, y, params_.patch_half_px)) return false;
  d0 = std::max(d0, params_.min_disp_px);
  d1 = std::min(d1, params_.max_disp_px - 1);
  out = StereoMatch{};
  out.u_px = static_cast<float>(x);
  out.v_px = static_cast<float>(y);
  return searchRow(left, right, x, y, d0, d1, out);
}

Status StereoPointMatcher::process(ImageView<const std::uint8_t> left,
                                   ImageView<const std::uint8_t> right,
                                   const std::vector<Eigen::Vector2f>& pts_px,
                                   ImageView<const float> prior_disp_px,
                                   std::vector<StereoMatch>& out, StereoMatchStats& stats,
                                   const std::vector<Eigen::Vector2i>* ranges) {
  out.clear();
  stats = {};
  if (!init_status_) return init_status_;
  if (left.empty() || left.width != right.width || left.height != right.height)
    return Status::invalidArgument("stereo matcher: left and right images differ in size");
  const bool has_prior = !prior_disp_px.empty();
  if (has_prior && (prior_disp_px.width != left.width || prior_disp_px.height != left.height))
    return Status::invalidArgument("stereo matcher: disparity prior size differs from the image");
  if (ranges && ranges->size() != pts_px.size())
    return Status::invalidArgument("stereo matcher: one disparity range per point expected");
  const int h = params_.patch_half_px;
  for (std::size_t i = 0; i < pts_px.size(); ++i) {
    const int x = static_cast<int>(std::lround(pts_px[i].x()));
    const int y = static_cast<int>(std::lround(pts_px[i].y()));
    if (!patchInside(left, x, y, h)) continue;
    ++stats.candidates;
    int d0 = params_.min_disp_px, d1 = params_.max_disp_px - 1;
    if (ranges) {
      d0 = std::max(d0, (*ranges)[i].x());
      d1 = std::min(d1, (*ranges)[i].y());
      if (d0 > d1) continue;
    }
    if (has_prior) {
      const float p = prior_disp_px(x, y);
      if (std::isfinite(p)) {
        d0 = std::max(d0, static_cast<int>(std::floor(p)) - params_.prior_radius_px);
        d1 = std::min(d1, static_cast<int>(std::ceil(p)) + params_.prior_radius_px);
      }
    }
    StereoMatch m;
    if (!searchRow(left, right, x, y, d0, d1, m)) continue;
    m.index = static_cast<int>(i);
    m.u_px = pts_px[i].x();
    m.v_px = pts_px[i].y();
    out.push_back(m);
  }
  stats.row_matched = static_cast<int>(out.size());
  rejected_.clear();
  if (params_.continuity_check) continuityCheck(out, rejected_);
  stats.continuity_rejected = static_cast<int>(rejected_.size());
  if (params_.recovery && !rejected_.empty()) recover(left, right, out, rejected_);
  for (const StereoMatch& m : out) {
    stats.recovered += m.recovered ? 1 : 0;
    stats.refined += m.refined ? 1 : 0;
  }
  std::sort(out.begin(), out.end(),
            [](const StereoMatch& a, const StereoMatch& b) { return a.index < b.index; });
  stats.matched = static_cast<int>(out.size());
  return Status::ok();
}

void StereoPointMatcher::continuityCheck(std::vector<StereoMatch>& matches,
                                         std::vector<StereoMatch>& rejected) {
  const std::size_t n = matches.size();
  keep_.assign(n, 1);
  if (n < 4) return;
  for (std::size_t i = 0; i < n; ++i) {
    // The 3 nearest neighbours in the left image (brute force, n is a few thousand at most).
    float bd[3] = {HUGE_VALF, HUGE_VALF, HUGE_VALF};
    std::size_t bi[3] = {0, 0, 0};
    for (std::size_t j = 0; j < n; ++j) {
      if (j == i) continue;
      const float dx = matches[j].u_px - matches[i].u_px, dy = matches[j].v_px - matches[i].v_px;
      const float d2 = dx * dx + dy * dy;
      if (d2 >= bd[2]) continue;
      int k = 2;
      while (k > 0 && d2 < bd[k - 1]) {
        bd[k] = bd[k - 1];
        bi[k] = bi[k - 1];
        --k;
      }
      bd[k] = d2;
      bi[k] = j;
    }
    for (int k = 0; k < 3; ++k)
      if (!(std::abs(matches[i].d_px - matches[bi[k]].d_px) < params_.continuity_threshold_px))
        keep_[i] = 0;
  }
  std::size_t w = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (keep_[i])
      matches[w++] = matches[i];
    else
      rejected.push_back(matches[i]);
  }
  matches.resize(w);
}

void StereoPointMatcher::recover(ImageView<const std::uint8_t> left,
                                 ImageView<const std::uint8_t> right,
                                 std::vector<StereoMatch>& kept,
                                 const std::vector<StereoMatch>& rejected) {
  const std::size_t n_kept = kept.size();
  if (n_kept < 3) return;
  tri_pts_.resize(n_kept);
  for (std::size_t i = 0; i < n_kept; ++i) tri_pts_[i] = {kept[i].u_px, kept[i].v_px};
  if (!delaunay_.process(tri_pts_, tris_)) return;
  const int h = params_.patch_half_px;
  for (const StereoMatch& r : rejected) {
    const Eigen::Vector2d pa(r.u_px, r.v_px);
    Eigen::Vector3d bary;
    const int t = Delaunay::locate(tri_pts_, tris_, pa, bary);
    if (t < 0) continue;
    const auto& v = tris_[static_cast<std::size_t>(t)].v;
    float dmin = HUGE_VALF, dmax = -HUGE_VALF;
    for (int k = 0; k < 3; ++k) {
      dmin = std::min(dmin, kept[static_cast<std::size_t>(v[k])].d_px);
      dmax = std::max(dmax, kept[static_cast<std::size_t>(v[k])].d_px);
    }
    const int x = static_cast<int>(std::lround(r.u_px));
    const int y = static_cast<int>(std::lround(r.v_px));
    const int d0 = std::max(params_.min_disp_px,
                            static_cast<int>(std::floor(dmin)) - params_.recovery_margin_px - 1);
    const int d1 = std::min({params_.max_disp_px - 1, x - h,
                             static_cast<int>(std::ceil(dmax)) + params_.recovery_margin_px + 1});
    if (d1 - d0 < 2) continue;
    const PatchStats ps = patchStats(left, x, y, h);
    if (ps.inv_norm == 0.0) continue;
    scanRow(left, right, ps, y, d0, d1);
    float best_cost = params_.recovery_dist_th_px;
    StereoMatch best = r;
    bool found = false;
    for (int i = 1; i < d1 - d0; ++i) {
      const float s0 = scores_[static_cast<std::size_t>(i)];
      const float sm = scores_[static_cast<std::size_t>(i - 1)];
      const float sp = scores_[static_cast<std::size_t>(i + 1)];
      if (s0 < params_.min_zncc || s0 < sm || s0 < sp) continue;
      StereoMatch cand = r;
      setPeak(left, right, x, y, d0 + i, sm, s0, sp, cand);
      const Eigen::Vector2d pb(r.u_px - cand.d_px, r.v_px);
      double cost = 0;
      for (int k = 0; k < 3; ++k) {
        const StereoMatch& vk = kept[static_cast<std::size_t>(v[k])];
        const Eigen::Vector2d pav(vk.u_px, vk.v_px), pbv(vk.u_px - vk.d_px, vk.v_px);
        cost += std::abs((pa - pav).norm() - (pb - pbv).norm());
      }
      if (cost < best_cost) {
        best_cost = static_cast<float>(cost);
        best = cand;
        found = true;
      }
    }
    if (found) {
      best.recovered = true;
      kept.push_back(best);
    }
  }
}

}  // namespace svslam
