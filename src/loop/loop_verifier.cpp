#include "loop/loop_verifier.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace svslam {

VisualMotionParams LoopVerifierParams::defaultMotion() {
  VisualMotionParams p;
  p.ransac = true;
  p.ransac_iterations = 300;
  p.min_inliers = 6;
  p.seed = 1;
  return p;
}

Status LoopVerifierParams::validate() const {
  if (max_hamming < 1 || max_hamming > 256)
    return Status::invalidArgument("loop.verify max_hamming must be in 1..256");
  if (!(max_ratio > 0 && max_ratio <= 1))
    return Status::invalidArgument("loop.verify max_ratio must be in (0, 1]");
  if (min_inliers < 6) return Status::invalidArgument("loop.verify min_inliers must be >= 6");
  if (!(min_inlier_fraction >= 0 && min_inlier_fraction <= 1))
    return Status::invalidArgument("loop.verify min_inlier_fraction must be in [0, 1]");
  if (!(max_rms_mahalanobis > 0) || !std::isfinite(max_rms_mahalanobis))
    return Status::invalidArgument("loop.verify max_rms_mahalanobis must be > 0");
  return motion.validate();
}

namespace {
// Nearest and second-nearest of d among set (distances), index of the nearest.
void nearest(const OrbDescriptor& d, const std::vector<OrbDescriptor>& set, int& best, int& d1,
             int& d2) {
  best = -1;
  d1 = d2 = std::numeric_limits<int>::max();
  for (std::size_t j = 0; j < set.size(); ++j) {
    const int h = hammingDistance(d, set[j]);
    if (h < d1) {
      d2 = d1;
      d1 = h;
      best = static_cast<int>(j);
    } else if (h < d2) {
      d2 = h;
    }
  }
}
}  // namespace

void matchDescriptors(const std::vector<OrbDescriptor>& a, const std::vector<OrbDescriptor>& b,
                      int max_hamming, double max_ratio, std::vector<std::pair<int, int>>& matches) {
  matches.clear();
  std::vector<int> back(b.size(), -2);  // nearest of b[j] in a, computed lazily
  for (std::size_t i = 0; i < a.size(); ++i) {
    int j, d1, d2;
    nearest(a[i], b, j, d1, d2);
    if (j < 0 || d1 > max_hamming) continue;
    if (d2 != std::numeric_limits<int>::max() && d1 > max_ratio * d2) continue;
    if (back[static_cast<std::size_t>(j)] == -2) {
      int i2, e1, e2;
      nearest(b[static_cast<std::size_t>(j)], a, i2, e1, e2);
      back[static_cast<std::size_t>(j)] = i2;
    }
    if (back[static_cast<std::size_t>(j)] != static_cast<int>(i)) continue;
    matches.emplace_back(static_cast<int>(i), j);
  }
}

LoopVerifier::LoopVerifier(const LoopVerifierParams& params)
    : params_(params), motion_(params.motion) {
  init_status_ = params.validate();
  if (init_status_) init_status_ = motion_.initStatus();
}

Status LoopVerifier::process(const Keyframe& query, const Keyframe& candidate, LoopConstraint& out) {
  if (!init_status_) return init_status_;
  out = LoopConstraint{};
  out.query = query.id;
  out.candidate = candidate.id;
  const auto consistent = [](const Keyframe& k) {
    return k.uv_px.size() == k.size() && k.disparity_px.size() == k.size() &&
           k.sigma_d_px.size() == k.size();
  };
  if (!consistent(query) || !consistent(candidate))
    return Status::invalidArgument("loop verifier: keyframe points and descriptors differ in count");
  std::vector<std::pair<int, int>> matches;
  matchDescriptors(query.descriptors, candidate.descriptors, params_.max_hamming,
                   params_.max_ratio, matches);
  out.matches = static_cast<int>(matches.size());
  if (out.matches < params_.min_inliers) {
    out.reason = "too few descriptor matches";
    return Status::ok();
  }
  pairs_.clear();
  for (const auto& [iq, ic] : matches) {
    const StereoPoint c = candidate.point(static_cast<std::size_t>(ic));
    const StereoPoint q = query.point(static_cast<std::size_t>(iq));
    PointPair p;
    p.p_prev = c.p_cam;
    p.cov_prev = c.cov;
    p.p_cur = q.p_cam;
    p.cov_cur = q.cov;
    pairs_.push_back(p);
  }
  const Status s = motion_.process(pairs_, result_);
  if (!s) {
    out.reason = "motion estimation failed: " + s.message();
    return Status::ok();
  }
  out.inliers = result_.used;
  out.rms_mahalanobis = result_.rms_mahalanobis;
  out.T_query_candidate = result_.T_cur_prev;
  out.covariance = result_.covariance;
  if (out.inliers < params_.min_inliers) {
    out.reason = "too few inliers";
  } else if (out.inliers < params_.min_inlier_fraction * out.matches) {
    out.reason = "inlier fraction too low";
  } else if (out.rms_mahalanobis > params_.max_rms_mahalanobis) {
    out.reason = "residuals too large";
  } else if (!out.T_query_candidate.matrix().allFinite() || !out.covariance.allFinite()) {
    out.reason = "non-finite estimate";
  } else {
    out.accepted = true;
  }
  return Status::ok();
}

}  // namespace svslam
