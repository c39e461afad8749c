// SlamSystem, the return of retired anchors (step 5 of slam_system.hpp): a first-frame landmark
// retired to bound the state is searched again whenever it is predicted inside the current
// image, and put back into the state when it is found, so that a loop closes on the landmarks of
// its start.
#include <algorithm>
#include <cmath>

#include "slam/slam_system.hpp"

namespace svslam {

void SlamSystem::restoreAnchors(ImageView<const std::uint8_t> left, SlamFrameResult& out,
                                const std::vector<Eigen::Vector2f>* corners) {
  if (params_.max_reperceptions == 0) return;
  const Eigen::Isometry3d T_wc = ekf_.pose();
  const Matrix6d P_pose = ekf_.poseCovariance();
  std::vector<SearchPrediction>& preds = retired_preds_;
  preds.clear();
  for (const int id : anchored_ids_) {
    const MapLandmark& lm = landmarks_.info(id);
    if (lm.active) continue;
    SearchPrediction pr;
    if (!predictLandmark(lm.p_world, lm.cov, T_wc, P_pose, pr) || !std::isfinite(pr.sigma_px))
      continue;
    pr.id = lm.id;
    preds.push_back(pr);
  }
  // The best predicted first (they are the most likely found, and the most precise); ties by id.
  std::sort(preds.begin(), preds.end(), [](const SearchPrediction& a, const SearchPrediction& c) {
    if (a.sigma_px != c.sigma_px) return a.sigma_px < c.sigma_px;
    return a.id < c.id;
  });
  int searched = 0;
  for (const SearchPrediction& pr : preds) {
    if (searched >= params_.max_reperceptions) break;
    ++searched;
    const int r = searchRadius(pr, params_.reperception_tolerance_px);
    PatchStats ps;
    if (!warpTemplate(pr, T_wc.linear(), ps)) continue;
    if (corners ? !nearCornerMatches(left, templateView(), ps, pr, r, *corners)
                : bestStereoPoint(left, templateView(), ps, pr, r) < 0)
      continue;
    if (!makeRoom(out)) break;
    MapLandmark& lm = landmarks_.info(pr.id);
    if (!ekf_.restoreLandmark(pr.id, lm.p_world, lm.cov)) continue;
    lm.active = true;
    // Not retired again this frame (makeRoom), searched as a re-perception (not tracked).
    lm.last_seen_frame = frame_;
    ++out.restored;
  }
}

bool SlamSystem::nearCornerMatches(ImageView<const std::uint8_t> left,
                                   ImageView<const std::uint8_t> patch, const PatchStats& ps,
                                   const SearchPrediction& pr, int r,
                                   const std::vector<Eigen::Vector2f>& corners) const {
  const int h = params_.patch_half_px;
  for (const Eigen::Vector2f& c : corners) {
    const double du = c.x() - pr.u, dv = c.y() - pr.v;
    if (du * du + dv * dv > static_cast<double>(r) * r) continue;
    const int x = static_cast<int>(std::lround(c.x())), y = static_cast<int>(std::lround(c.y()));
    if (patchInside(left, x, y, h) && zncc(patch, ps, left, x, y) > params_.reperception_min_zncc)
      return true;
  }
  return false;
}

}  // namespace svslam
