#include "features/temporal_matcher.hpp"

#include <algorithm>
#include <cmath>

#include "features/patch_similarity.hpp"

namespace svslam {

Status TemporalMatchParams::validate() const {
  if (patch_half_px < 1 || patch_half_px > 15)
    return Status::invalidArgument("temporal_match.patch_half_px must be in 1..15");
  if (!(search_radius_px > 0.0f) || !std::isfinite(search_radius_px))
    return Status::invalidArgument("temporal_match.search_radius_px must be > 0");
  if (!(min_zncc >= -1.0f && min_zncc <= 1.0f))
    return Status::invalidArgument("temporal_match.min_zncc must be in -1..1");
  if (!(ratio > 0.0f && ratio <= 1.0f))
    return Status::invalidArgument("temporal_match.ratio must be in (0, 1]");
  if (group_size < 0 || group_size > 32)
    return Status::invalidArgument("temporal_match.group_size must be in 0..32");
  if (!(group_n_sigma > 0.0) || !std::isfinite(group_n_sigma))
    return Status::invalidArgument("temporal_match.group_n_sigma must be > 0");
  if (!(group_min_fraction >= 0.0 && group_min_fraction <= 1.0))
    return Status::invalidArgument("temporal_match.group_min_fraction must be in 0..1");
  return Status::ok();
}

TemporalMatcher::TemporalMatcher(const TemporalMatchParams& params)
    : params_(params), init_status_(params.validate()) {
  // Per point of a frame; grown once past this when a frame has more points.
  constexpr std::size_t kPoints = 2048;
  order_.reserve(kPoints);
  fill_.reserve(kPoints);
  best_prev_of_cur_.reserve(kPoints);
  best_score_of_cur_.reserve(kPoints);
  cand_.reserve(kPoints);
  keep_.reserve(kPoints);
  neighbours_.reserve(kPoints);
}

void TemporalMatcher::buildGrid(const std::vector<TrackPoint>& cur, int width, int height,
                                float cell) {
  cell_ = cell;
  grid_w_ = std::max(1, static_cast<int>(std::ceil(static_cast<float>(width) / cell)));
  grid_h_ = std::max(1, static_cast<int>(std::ceil(static_cast<float>(height) / cell)));
  const std::size_t nc = static_cast<std::size_t>(grid_w_) * static_cast<std::size_t>(grid_h_);
  start_.assign(nc + 1, 0);
  auto cellOf = [&](const TrackPoint& p) {
    const int cx = std::clamp(static_cast<int>(p.u_px / cell), 0, grid_w_ - 1);
    const int cy = std::clamp(static_cast<int>(p.v_px / cell), 0, grid_h_ - 1);
    return static_cast<std::size_t>(cy * grid_w_ + cx);
  };
  for (const TrackPoint& p : cur) ++start_[cellOf(p) + 1];
  for (std::size_t c = 0; c < nc; ++c) start_[c + 1] += start_[c];
  fill_.assign(start_.begin(), start_.end() - 1);
  order_.resize(cur.size());
  for (std::size_t i = 0; i < cur.size(); ++i)
    order_[static_cast<std::size_t>(fill_[cellOf(cur[i])]++)] = static_cast<int>(i);
}

Status TemporalMatcher::process(ImageView<const std::uint8_t> prev_img,
                                const std::vector<TrackPoint>& prev,
                                ImageView<const std::uint8_t> cur_img,
                                const std::vector<TrackPoint>& cur,
                                const Eigen::Isometry3d& T_cur_prev_pred,
                                const PinholeCamera& camera, std::vector<TemporalMatch>& out,
                                TemporalMatchStats& stats, float search_radius_px,
                                const std::vector<Eigen::Vector4i>* regions) {
  out.clear();
  stats = {};
  if (!init_status_) return init_status_;
  if (prev_img.width != cur_img.width || prev_img.height != cur_img.height)
    return Status::invalidArgument("temporal matcher: images differ in size");
  if (regions && regions->size() != prev.size())
    return Status::invalidArgument("temporal matcher: one region per previous point expected");
  const float radius = search_radius_px > 0.0f ? search_radius_px : params_.search_radius_px;
  const int h = params_.patch_half_px;
  buildGrid(cur, cur_img.width, cur_img.height, std::max(8.0f, radius));
  best_prev_of_cur_.assign(cur.size(), -1);
  best_score_of_cur_.assign(cur.size(), -2.0f);
  cand_.clear();
  const float r2 = radius * radius;
  for (std::size_t i = 0; i < prev.size(); ++i) {
    const Eigen::Vector3d q = T_cur_prev_pred * prev[i].p_cam;
    double u, v;
    if (!camera.project(q.x(), q.y(), q.z(), u, v)) continue;
    if (u < -radius || v < -radius || u >= cur_img.width + radius ||
        v >= cur_img.height + radius)
      continue;
    const int px = static_cast<int>(std::lround(prev[i].u_px));
    const int py = static_cast<int>(std::lround(prev[i].v_px));
    if (!patchInside(prev_img, px, py, h)) continue;
    ++stats.predicted;
    const PatchStats ps = patchStats(prev_img, px, py, h);
    if (ps.inv_norm == 0.0) continue;
    const int cx0 = std::max(0, static_cast<int>((static_cast<float>(u) - radius) / cell_));
    const int cx1 = std::min(grid_w_ - 1, static_cast<int>((static_cast<float>(u) + radius) / cell_));
    const int cy0 = std::max(0, static_cast<int>((static_cast<float>(v) - radius) / cell_));
    const int cy1 = std::min(grid_h_ - 1, static_cast<int>((static_cast<float>(v) + radius) / cell_));
    float best = -2.0f, second = -2.0f;
    int best_j = -1;
    for (int cy = cy0; cy <= cy1; ++cy)
      for (int cx = cx0; cx <= cx1; ++cx) {
        const std::size_t c = static_cast<std::size_t>(cy * grid_w_ + cx);
        for (int k = start_[c]; k < start_[c + 1]; ++k) {
          const int j = order_[static_cast<std::size_t>(k)];
          const TrackPoint& cj = cur[static_cast<std::size_t>(j)];
          const float du = cj.u_px - static_cast<float>(u), dv = cj.v_px - static_cast<float>(v);
          if (du * du + dv * dv > r2) continue;
          if (regions) {
            const Eigen::Vector4i& g = (*regions)[i];
            if (g[0] < g[2] && (cj.u_px < g[0] || cj.u_px >= g[2] || cj.v_px < g[1] ||
                                cj.v_px >= g[3]))
              continue;
          }
          const int qx = static_cast<int>(std::lround(cj.u_px));
          const int qy = static_cast<int>(std::lround(cj.v_px));
          if (!patchInside(cur_img, qx, qy, h)) continue;
          const float s = zncc(prev_img, ps, cur_img, qx, qy);
          if (s > best) {
            second = best;
            best = s;
            best_j = j;
          } else if (s > second) {
            second = s;
          }
        }
      }
    if (best_j < 0 || best < params_.min_zncc) continue;
    if (second > -2.0f && 1.0f - best > params_.ratio * (1.0f - second)) continue;
    cand_.push_back({static_cast<int>(i), best_j, best});
    const std::size_t bj = static_cast<std::size_t>(best_j);
    if (best > best_score_of_cur_[bj]) {
      best_score_of_cur_[bj] = best;
      best_prev_of_cur_[bj] = static_cast<int>(i);
    }
  }
  for (const TemporalMatch& m : cand_)
    if (best_prev_of_cur_[static_cast<std::size_t>(m.cur)] == m.prev) out.push_back(m);
  stats.signal_matched = static_cast<int>(out.size());
  if (params_.group_size > 0) geometricCheck(prev, cur, out);
  stats.geometry_rejected = stats.signal_matched - static_cast<int>(out.size());
  stats.matched = static_cast<int>(out.size());
  return Status::ok();
}

void TemporalMatcher::geometricCheck(const std::vector<TrackPoint>& prev,
                                     const std::vector<TrackPoint>& cur,
                                     std::vector<TemporalMatch>& matches) {
  const std::size_t n = matches.size();
  const int g = std::min<int>(params_.group_size, static_cast<int>(n) - 1);
  if (g < 2) return;
  keep_.assign(n, 0);
  std::vector<std::pair<float, int>>& nb = neighbours_;
  for (std::size_t i = 0; i < n; ++i) {
    const TrackPoint& pi = prev[static_cast<std::size_t>(matches[i].prev)];
    const TrackPoint& ci = cur[static_cast<std::size_t>(matches[i].cur)];
    nb.clear();
    for (std::size_t j = 0; j < n; ++j) {
      if (j == i) continue;
      const TrackPoint& pj = prev[static_cast<std::size_t>(matches[j].prev)];
      const float du = pj.u_px - pi.u_px, dv = pj.v_px - pi.v_px;
      nb.emplace_back(du * du + dv * dv, static_cast<int>(j));
    }
    std::partial_sort(nb.begin(), nb.begin() + g, nb.end());
    int agree = 0;
    for (int k = 0; k < g; ++k) {
      const std::size_t j = static_cast<std::size_t>(nb[static_cast<std::size_t>(k)].second);
      const TrackPoint& pj = prev[static_cast<std::size_t>(matches[j].prev)];
      const TrackPoint& cj = cur[static_cast<std::size_t>(matches[j].cur)];
      const Eigen::Vector3d a = pi.p_cam - pj.p_cam, b = ci.p_cam - cj.p_cam;
      const double da = a.norm(), db = b.norm();
      if (da < 1e-9 || db < 1e-9) continue;
      const Eigen::Vector3d ua = a / da, ub = b / db;
      const double var = ua.dot((pi.cov + pj.cov) * ua) + ub.dot((ci.cov + cj.cov) * ub);
      if (std::abs(da - db) <= params_.group_n_sigma * std::sqrt(var)) ++agree;
    }
    keep_[i] = agree >= params_.group_min_fraction * g ? 1 : 0;
  }
  std::size_t w = 0;
  for (std::size_t i = 0; i < n; ++i)
    if (keep_[i]) matches[w++] = matches[i];
  matches.resize(w);
}

}  // namespace svslam
