// SlamSystem, steps 3-5 of slam_system.hpp: the search of the state's landmarks in the current
// pair (observations for the EKF update) and the landmark selection (candidates, promotion into
// the filter, retirement to make room).
#include <algorithm>
#include <cmath>
#include <limits>

#include "features/patch_similarity.hpp"
#include "features/subpixel_refine.hpp"
#include "slam/slam_system.hpp"
#include "stereo/reprojection.hpp"

namespace svslam {

namespace {

float parabolaOffset(float m, float c, float p) {
  const float den = m - 2.0f * c + p;
  return den < 0.0f ? std::clamp(0.5f * (m - p) / den, -0.5f, 0.5f) : 0.0f;
}

// A sort key with NaN (never expected) placed last, so comparisons stay a strict weak order.
double orderKey(double v) { return std::isnan(v) ? std::numeric_limits<double>::infinity() : v; }

}  // namespace

bool SlamSystem::predictLandmark(const Eigen::Vector3d& m, const Eigen::Matrix3d& C,
                                 const Eigen::Isometry3d& T_wc, const Matrix6d& P_pose,
                                 SearchPrediction& pr) const {
  const int h = params_.patch_half_px;
  const double f = calib_.f_px, b = calib_.baseline_m;
  const Eigen::Matrix3d Rt = T_wc.linear().transpose();
  const Eigen::Vector3d dm = m - T_wc.translation();
  const Eigen::Vector3d z = Rt * dm;
  if (!(z.z() > 0.1)) return false;
  pr.u = f * z.x() / z.z() + calib_.cx_px;
  pr.v = f * z.y() / z.z() + calib_.cy_px;
  pr.d = f * b / z.z();
  pr.z_cam = z;
  if (pr.u < h + 1 || pr.v < h + 1 || pr.u >= calib_.width - h - 2 || pr.v >= calib_.height - h - 2)
    return false;
  // Covariance of the predicted camera-frame point (pose and landmark; the cross terms are
  // left out, which overstates the spread: a wider search, never a narrower one):
  // z = R^T (m - t), dz/d(dtheta) = R^T [m - t]x, dz/d(dt) = -R^T, dz/dm = R^T.
  Eigen::Matrix<double, 3, 6> J;
  Eigen::Matrix3d sk;
  sk << 0, -dm.z(), dm.y(), dm.z(), 0, -dm.x(), -dm.y(), dm.x(), 0;
  J.leftCols<3>() = Rt * sk;
  J.rightCols<3>() = -Rt;
  const Eigen::Matrix3d Cz = J * P_pose * J.transpose() + Rt * C * Rt.transpose();
  Eigen::Matrix<double, 3, 3> Jp;  // d(u, v, d)/dz
  const double iz = 1.0 / z.z();
  Jp << f * iz, 0, -f * z.x() * iz * iz, 0, f * iz, -f * z.y() * iz * iz, 0, 0, -f * b * iz * iz;
  const Eigen::Matrix3d Cuvd = Jp * Cz * Jp.transpose();
  pr.sigma_px = std::sqrt(std::max({Cuvd(0, 0), Cuvd(1, 1), 0.0}));
  pr.sigma_d = std::sqrt(std::max(Cuvd(2, 2), 0.0));
  return true;
}

int SlamSystem::searchRadius(const SearchPrediction& pr, double tolerance_px) const {
  return static_cast<int>(
      std::ceil(std::min(tolerance_px + 3.0 * pr.sigma_px, params_.reperception_max_radius_px)));
}

bool SlamSystem::warpTemplate(const SearchPrediction& pr, const Eigen::Matrix3d& R_world_cam,
                              PatchStats& ps) {
  if (!landmarks_.templateFor(pr.id, R_world_cam, pr.z_cam, calib_.f_px, tmpl_.data()))
    return false;
  const int h = params_.patch_half_px;
  ps = patchStats(templateView(), h, h, h);
  return ps.inv_norm != 0.0;
}

int SlamSystem::bestStereoPoint(ImageView<const std::uint8_t> left,
                                ImageView<const std::uint8_t> patch, const PatchStats& ps,
                                const SearchPrediction& pr, int r) const {
  const int h = params_.patch_half_px;
  const auto& pts = vo_.points();
  int best_j = -1;
  float best_s = params_.reperception_min_zncc;
  for (std::size_t j = 0; j < pts.size(); ++j) {
    const double du = pts[j].u_px - pr.u, dv = pts[j].v_px - pr.v;
    if (du * du + dv * dv > static_cast<double>(r) * r) continue;
    const int x = static_cast<int>(std::lround(pts[j].u_px));
    const int y = static_cast<int>(std::lround(pts[j].v_px));
    if (!patchInside(left, x, y, h)) continue;
    const float sc = zncc(patch, ps, left, x, y);
    if (sc > best_s) {
      best_s = sc;
      best_j = static_cast<int>(j);
    }
  }
  return best_j;
}

void SlamSystem::searchLandmarks(ImageView<const std::uint8_t> left,
                                 ImageView<const std::uint8_t> right, SlamFrameResult& out,
                                 SearchPass pass, int already) {
  obs_.clear();
  bobs_.clear();
  obs_uv_.clear();
  const bool stereo = !right.empty();
  const int h = params_.patch_half_px;
  const Eigen::Isometry3d T_wc = ekf_.pose();
  const Matrix6d P_pose = ekf_.poseCovariance();
  std::vector<SearchPrediction>& preds = preds_;
  preds.clear();
  for (const int id : ekf_.landmarkIds()) {
    Eigen::Vector3d m;
    Eigen::Matrix3d C;
    if (!ekf_.landmark(id, m, C)) continue;
    SearchPrediction pr;
    if (!predictLandmark(m, C, T_wc, P_pose, pr)) continue;
    pr.id = id;
    const int last_seen = landmarks_.info(id).last_seen_frame;
    pr.tracked = last_seen == frame_ - 1;
    if (pass == SearchPass::kFirst && !pr.tracked) continue;
    if (pass == SearchPass::kRest && last_seen == frame_) continue;  // observed (or restored)
    pr.order = static_cast<int>(preds.size());
    preds.push_back(pr);
    if (pass != SearchPass::kRest) ++out.predicted_visible;
  }
  int max_obs = params_.max_observations - already;
  if (pass == SearchPass::kFirst) {
    // The best predicted first (the smallest windows: the least likely mismatched).
    std::sort(preds.begin(), preds.end(),
              [](const SearchPrediction& a, const SearchPrediction& c) {
                const double sa = orderKey(a.sigma_px), sc = orderKey(c.sigma_px);
                return sa != sc ? sa < sc : a.order < c.order;
              });
  }
  // Order of the searches: re-perceptions first (the best predicted first, at most
  // max_reperceptions: they close loops), then the tracked landmarks, oldest first (they carry
  // the longest memory); at most max_observations observations per frame (bounded update cost).
  if (pass != SearchPass::kFirst)
  std::sort(preds.begin(), preds.end(), [&](const SearchPrediction& a, const SearchPrediction& c) {
    if (a.tracked != c.tracked) return !a.tracked;
    if (!a.tracked) {
      const double sa = orderKey(a.sigma_px), sc = orderKey(c.sigma_px);
      if (sa != sc) return sa < sc;
    } else {
      const int fa = landmarks_.info(a.id).created_frame, fc = landmarks_.info(c.id).created_frame;
      if (fa != fc) return fa < fc;
    }
    return a.order < c.order;
  });
  int reperceptions = 0;
  for (const SearchPrediction& pr : preds) {
    if (static_cast<int>(obs_uv_.size()) >= max_obs) break;
    if (!pr.tracked && reperceptions >= params_.max_reperceptions) continue;
    if (!pr.tracked) ++reperceptions;
    const double tol = pr.tracked ? params_.track_tolerance_px : params_.reperception_tolerance_px;
    const int r = searchRadius(pr, tol);
    const int x0 = std::max(h + 1, static_cast<int>(std::lround(pr.u)) - r);
    const int x1 = std::min(calib_.width - h - 2, static_cast<int>(std::lround(pr.u)) + r);
    const int y0 = std::max(h + 1, static_cast<int>(std::lround(pr.v)) - r);
    const int y1 = std::min(calib_.height - h - 2, static_cast<int>(std::lround(pr.v)) + r);
    if (x1 < x0 || y1 < y0) continue;
    PatchStats ps;
    if (!warpTemplate(pr, T_wc.linear(), ps)) continue;
    const ImageView<const std::uint8_t> patch = templateView();
    if (!pr.tracked && stereo) {
      // Re-perception: among this frame's stereo points near the prediction (cheap, and the
      // point already has its disparity).
      const int best_j = bestStereoPoint(left, patch, ps, pr, r);
      StereoPoint sp;
      if (best_j < 0) {
        ++out.search_no_match;
        continue;
      }
      const TrackPoint& tp = vo_.points()[static_cast<std::size_t>(best_j)];
      if (!vo_.observe(tp, params_.reperception_matching_error_px, sp)) continue;
      obs_.push_back({pr.id, sp.p_cam, sp.cov});
      obs_uv_.emplace_back(tp.u_px, tp.v_px);
      ++out.reperceived;
      continue;
    }
    const int w = x1 - x0 + 1;
    scores_.assign(static_cast<std::size_t>(w * (y1 - y0 + 1)), -2.0f);
    int bx = -1, by = -1;
    float best = params_.reperception_min_zncc;
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const float sc = zncc(patch, ps, left, x, y);
        scores_[static_cast<std::size_t>((y - y0) * w + (x - x0))] = sc;
        if (sc > best) {
          best = sc;
          bx = x;
          by = y;
        }
      }
    if (bx < 0) {
      ++out.search_no_match;
      continue;
    }
    auto at = [&](int x, int y) {
      if (x < x0 || x > x1 || y < y0 || y > y1) return zncc(patch, ps, left, x, y);
      return scores_[static_cast<std::size_t>((y - y0) * w + (x - x0))];
    };
    float u = static_cast<float>(bx) + parabolaOffset(at(bx - 1, by), best, at(bx + 1, by));
    float v = static_cast<float>(by) + parabolaOffset(at(bx, by - 1), best, at(bx, by + 1));
    // Gauss-Newton refinement of the template's position (no pull towards integer pixels);
    // the parabola stays when it does not converge.
    double u_ref = 0.0, v_ref = 0.0;
    if (params_.refine_observations &&
        refineTranslation(tmpl_.data(), h, left, u, v, SubpixelRefineParams{}, u_ref, v_ref)) {
      u = static_cast<float>(u_ref);
      v = static_cast<float>(v_ref);
    }
    if (!stereo) {
      // Mono frame: the bearing, normalised image coordinates with the matching error.
      const double err =
          pr.tracked ? params_.mono_track_error_px : params_.mono_reperception_error_px;
      const double f = calib_.f_px, s_xy = err / f;
      bobs_.push_back({pr.id, Eigen::Vector2d((u - calib_.cx_px) / f, (v - calib_.cy_px) / f),
                       s_xy * s_xy * Eigen::Matrix2d::Identity()});
      obs_uv_.emplace_back(u, v);
      if (pr.tracked)
        ++out.observed;
      else
        ++out.reperceived;
      continue;
    }
    // Right image: along the row around the predicted disparity.
    const double dr = 3.0 * pr.sigma_d + 3.0;
    StereoMatch sm;
    if (!landmark_row_matcher_.matchPoint(left, right, bx, by, static_cast<int>(std::floor(pr.d - dr)),
                            static_cast<int>(std::ceil(pr.d + dr)), sm)) {
      ++out.search_no_stereo;
      continue;
    }
    const double err =
        pr.tracked ? params_.track_matching_error_px : params_.reperception_matching_error_px;
    TrackPoint tp;
    tp.u_px = u;
    tp.v_px = v;
    tp.d_px = sm.d_px;
    tp.sigma_d_px = sm.sigma_d_px;
    StereoPoint sp;
    if (!vo_.observe(tp, err, sp)) continue;
    obs_.push_back({pr.id, sp.p_cam, sp.cov});
    obs_uv_.emplace_back(u, v);
    if (pr.tracked)
      ++out.observed;
    else
      ++out.reperceived;
  }
}

bool SlamSystem::makeRoom(SlamFrameResult& out) {
  if (ekf_.numLandmarks() < params_.ekf.max_landmarks) return true;
  // The landmark unseen for the longest time (the smallest id on ties).
  int victim = -1, oldest = frame_ - params_.retire_unseen_frames + 1;
  for (const int id : ekf_.landmarkIds()) {
    const int seen = landmarks_.info(id).last_seen_frame;
    if (seen < oldest || (seen == oldest && victim >= 0 && id < victim)) {
      oldest = seen;
      victim = id;
    }
  }
  if (victim < 0) return false;
  MapLandmark& lm = landmarks_.info(victim);
  if (!ekf_.removeLandmark(victim, &lm.p_world, &lm.cov)) return false;
  landmarks_.retire(victim);
  ++out.retired;
  return true;
}

void SlamSystem::addAnchor(ImageView<const std::uint8_t> left, const TrackPoint& p,
                           PointTrack& track) {
  const int x = static_cast<int>(std::lround(p.u_px)), y = static_cast<int>(std::lround(p.v_px));
  // At the pixel its disparity was measured at, as for every landmark (below).
  const int big = 2 * params_.patch_half_px, side = 2 * big + 1;
  const std::size_t o = anchor_patches_.size();
  anchor_patches_.resize(o + static_cast<std::size_t>(side * side));
  LandmarkManager::copyPatch(left, x, y, big, anchor_patches_.data() + o);
  track.anchor = static_cast<int>(anchor_points_.size());
  anchor_points_.push_back(reprojectPixel(calib_, static_cast<float>(x), static_cast<float>(y),
                                          p.d_px, p.sigma_d_px, params_.init_sigma_uv_px));
}

std::size_t SlamSystem::gridCell(float u, float v) const {
  const int cx =
      std::clamp(static_cast<int>(u * params_.grid_cols / calib_.width), 0, params_.grid_cols - 1);
  const int cy = std::clamp(static_cast<int>(v * params_.grid_rows / calib_.height), 0,
                            params_.grid_rows - 1);
  return static_cast<std::size_t>(cy * params_.grid_cols + cx);
}

void SlamSystem::selectLandmarks(ImageView<const std::uint8_t> left, SlamFrameResult& out) {
  const auto& pts = vo_.points();
  const int h = params_.patch_half_px;
  const auto cellOf = [&](float u, float v) { return gridCell(u, v); };
  auto sigmaOf = [](const TrackPoint& p) { return std::sqrt(p.cov.trace()); };
  auto nearObserved = [&](const TrackPoint& p) {
    return nearLandmark(landmark_uv_, p.u_px, p.v_px);
  };
  std::fill(cell_count_.begin(), cell_count_.end(), 0);
  for (const Eigen::Vector2f& l : landmark_uv_) ++cell_count_[cellOf(l.x(), l.y())];
  for (std::size_t j = 0; j < pts.size(); ++j)
    if (cur_tracks_[j].candidate) ++cell_count_[cellOf(pts[j].u_px, pts[j].v_px)];

  // Promotion of stable candidates.
  for (std::size_t j = 0; j < pts.size(); ++j) {
    PointTrack& t = cur_tracks_[j];
    if (!t.candidate || t.track_len < params_.candidate_min_frames) continue;
    const TrackPoint& p = pts[j];
    if (sigmaOf(p) > params_.candidate_max_sigma_m || nearObserved(p)) {
      t.candidate = false;
      continue;
    }
    if (!makeRoom(out)) continue;  // stays a candidate
    if (t.anchor >= 0) {
      // A first-frame candidate: initialised from that frame, whose pose is exact.
      const StereoPoint& a = anchor_points_[static_cast<std::size_t>(t.anchor)];
      auto id = ekf_.addLandmarkFromExactPose(anchor_pose_, a.p_cam, a.cov);
      t.candidate = false;
      if (!id) continue;
      const int big = 2 * h, side = 2 * big + 1;
      const ImageView<const std::uint8_t> patch(
          anchor_patches_.data() + static_cast<std::size_t>(t.anchor * side * side), side, side,
          side);
      landmarks_.add(*id, frame_, patch, big, big, anchor_pose_, a.p_cam);
      landmarks_.info(*id).anchored = true;
      anchored_ids_.push_back(*id);
      landmark_uv_.emplace_back(p.u_px, p.v_px);
      ++out.added;
      continue;
    }
    // Initialised at the pixel its disparity was measured at (the row search runs on the
    // nearest pixel), which is also the centre of its appearance patch.
    const float x = std::round(p.u_px), y = std::round(p.v_px);
    const StereoPoint sp =
        reprojectPixel(calib_, x, y, p.d_px, p.sigma_d_px, params_.init_sigma_uv_px);
    auto id = ekf_.addLandmark(sp.p_cam, sp.cov);
    t.candidate = false;
    if (!id) continue;
    landmarks_.add(*id, frame_, left, static_cast<int>(x), static_cast<int>(y), ekf_.pose(),
                   sp.p_cam);
    landmark_uv_.emplace_back(x, y);
    ++out.added;
  }

  // New candidates among the points matched for the first time.
  std::vector<int>& fresh = fresh_;
  fresh.clear();
  for (std::size_t j = 0; j < pts.size(); ++j) {
    const PointTrack& t = cur_tracks_[j];
    const int x = static_cast<int>(std::lround(pts[j].u_px));
    const int y = static_cast<int>(std::lround(pts[j].v_px));
    if ((t.track_len == 2 || frame_ == 0) && !t.candidate && patchInside(left, x, y, h + 1) &&
        !nearObserved(pts[j]))
      fresh.push_back(static_cast<int>(j));
  }
  std::sort(fresh.begin(), fresh.end(), [&](int a, int c) {  // ties: ascending index, as inserted
    const double sa = orderKey(sigmaOf(pts[static_cast<std::size_t>(a)])),
                 sc = orderKey(sigmaOf(pts[static_cast<std::size_t>(c)]));
    return sa != sc ? sa < sc : a < c;
  });
  const int quota =
      static_cast<int>(std::ceil(params_.candidate_fraction * static_cast<double>(fresh.size())));
  int chosen = 0;
  for (const int j : fresh) {
    if (chosen >= quota) break;
    const TrackPoint& p = pts[static_cast<std::size_t>(j)];
    if (sigmaOf(p) > params_.candidate_max_sigma_m) continue;
    const std::size_t c = cellOf(p.u_px, p.v_px);
    if (cell_count_[c] >= params_.max_per_cell) continue;
    cur_tracks_[static_cast<std::size_t>(j)].candidate = true;
    if (frame_ == 0) addAnchor(left, p, cur_tracks_[static_cast<std::size_t>(j)]);
    ++cell_count_[c];
    ++chosen;
  }
  for (const PointTrack& t : cur_tracks_) out.candidates += t.candidate ? 1 : 0;
}

}  // namespace svslam
