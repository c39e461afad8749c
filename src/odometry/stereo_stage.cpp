#include "odometry/stereo_stage.hpp"

#include <algorithm>
#include <cmath>

namespace svslam {

namespace {
CornerParams detectorParams(const StereoOdometryParams& p) {
  CornerParams c = p.corners;
  // ROI tracking: the detector runs at the lowered threshold of the unknown cells; corners
  // inside ROIs are kept only at the normal one (applyRois).
  if (p.roi_tracking) c.threshold_rel *= p.unknown_threshold_factor;
  return c;
}
}  // namespace

bool stereoObservation(const StereoCalibration& calib, const DisparityResult* dense, float u_px,
                       float v_px, float d_px, float sigma_d_px, double matching_error_px,
                       StereoPoint& out) {
  if (dense)
    return neighbourhoodPoint(dense->disparity_px.cview(), dense->sigma_d_px.cview(), calib, u_px,
                              v_px, matching_error_px, 5, out);
  if (!(d_px > 0.0f)) return false;
  out = reprojectPixel(calib, u_px, v_px, d_px, sigma_d_px, matching_error_px);
  return out.p_cam.allFinite() && out.cov.allFinite();
}

void StereoStageOutput::clear() {
  has_disparity = false;
  left_only = false;
  finished = false;
  corner_px.clear();
  corner_resp.clear();
  max_response = 0.0f;
  stereo.clear();
  stereo_stats = StereoMatchStats{};
  points.clear();
  has_rois = false;
  rois = roi_dropped = unknown_corners = 0;
  prev_regions.clear();
}

StereoStage::StereoStage(const StereoOdometryParams& params, const StereoCalibration& calib)
    : params_(params),
      calib_(calib),
      detector_(detectorParams(params), std::max(calib.width, 1), std::max(calib.height, 1)),
      stereo_matcher_(params.stereo_match) {
  init_status_ = params.validate();
  if (init_status_) init_status_ = calib.validate();
  if (init_status_) init_status_ = detector_.initStatus();
  if (init_status_ && params.detector == PointDetector::kOrb) {
    orb_ = std::make_unique<OrbExtractor>(params.orb, calib.width, calib.height);
    init_status_ = orb_->initStatus();
  }
  if (init_status_ && params.dense) {
    dense_ = std::make_unique<DenseStereo>(params.dense_stereo, calib.width, calib.height);
    init_status_ = dense_->initStatus();
  }
  if (init_status_ && params.roi_tracking) {
    clusterer_ = std::make_unique<FeatureClusters>(params.clusters);
    init_status_ = clusterer_->initStatus();
  }
  if (init_status_) corners_.reserve(2048);
  // Points per frame: the detector's bucketing bounds them (cells x kept per cell).
  const bool orb = params.detector == PointDetector::kOrb;
  const int cells = orb ? params.orb.grid_cols * params.orb.grid_rows
                        : params.corners.grid_cols * params.corners.grid_rows;
  const int per_cell = orb ? params.orb.max_per_cell : params.corners.max_per_cell;
  max_points_ = static_cast<std::size_t>(cells) * static_cast<std::size_t>(per_cell);
}

StereoStage::~StereoStage() = default;

Status StereoStage::process(ImageView<const std::uint8_t> left, ImageView<const std::uint8_t> right,
                            const TrackingFeedback& feedback, StereoStageOutput& out,
                            Executor& executor, StageObserver* observer) {
  if (Status s = prepare(left, right, out, executor, observer); !s) return s;
  return finish(left, right, feedback, out, observer);
}

void StereoStage::prepareOutput(StereoStageOutput& out) const {
  if (!init_status_) return;
  out.corner_px.reserve(max_points_);
  out.corner_resp.reserve(max_points_);
  out.points.reserve(max_points_);
  out.stereo.reserve(max_points_);
  if (dense_) dense_->prepareOutput(out.disparity);
}

Status StereoStage::prepare(ImageView<const std::uint8_t> left, ImageView<const std::uint8_t> right,
                            StereoStageOutput& out, Executor& executor, StageObserver* observer) {
  if (!init_status_) return init_status_;
  const bool left_only = right.empty();
  if (left.width != calib_.width || left.height != calib_.height ||
      (!left_only && (right.width != calib_.width || right.height != calib_.height)))
    return Status::invalidArgument("stereo stage: image size differs from the calibration's");
  out.clear();
  out.left_only = left_only;
  // A pooled output is sized once for the bound (no growth frame after frame).
  out.corner_px.reserve(max_points_);
  out.corner_resp.reserve(max_points_);
  out.points.reserve(max_points_);
  if (dense_ && !left_only) {
    if (Status s = dense_->process(left, right, out.disparity, executor); !s) return s;
    out.has_disparity = true;
    if (observer) observer->stageDone("dense_stereo");
  }
  if (orb_) {
    if (Status s = orb_->process(left, orb_kp_, orb_desc_); !s) return s;
    for (const OrbKeypoint& k : orb_kp_) {
      out.corner_px.emplace_back(k.x_px, k.y_px);
      out.corner_resp.push_back(k.score);
    }
  } else {
    if (Status s = detector_.process(left, corners_, executor); !s) return s;
    for (const Corner& c : corners_) {
      out.corner_px.emplace_back(c.x_px, c.y_px);
      out.corner_resp.push_back(c.response);
    }
    out.max_response = detector_.lastMaxResponse();
  }
  if (observer) observer->stageDone("detect");
  return Status::ok();
}

Status StereoStage::finish(ImageView<const std::uint8_t> left, ImageView<const std::uint8_t> right,
                           const TrackingFeedback& feedback, StereoStageOutput& out,
                           StageObserver* observer) {
  if (!init_status_) return init_status_;
  if (right.empty()) {  // the right camera lost: corners only (no match, no point, no cluster)
    if (clusterer_) {
      prev_clusters_.clear();
      cur_clusters_.clear();
    }
    out.points.clear();
    prev_points_ = 0;
    out.finished = true;
    if (observer) observer->stageDone("stereo_match");
    return Status::ok();
  }
  if (clusterer_) {  // the last frame's clusters become the previous ones
    prev_clusters_.swap(cur_clusters_);
    cur_clusters_.clear();
    if (feedback.has_previous && !prev_clusters_.empty()) applyRois(feedback.T_cur_prev, out);
  }
  out.stereo.reserve(std::max(max_points_, out.corner_px.size()));  // at most one per point
  ImageView<const float> prior;
  if (out.has_disparity) prior = out.disparity.disparity_px.cview();
  if (Status s = stereo_matcher_.process(left, right, out.corner_px, prior, out.stereo,
                                         out.stereo_stats, out.has_rois ? &ranges_ : nullptr);
      !s)
    return s;
  buildPoints(out);
  if (clusterer_) {
    if (Status s = clusterPoints(out); !s) return s;
  }
  prev_points_ = out.points.size();
  out.finished = true;
  if (observer) observer->stageDone("stereo_match");
  return Status::ok();
}

void StereoStage::buildPoints(StereoStageOutput& out) const {
  out.points.clear();
  const DisparityResult* disp =
      out.has_disparity && params_.dense_observation ? &out.disparity : nullptr;
  const double min_d =
      std::max(params_.min_disparity_px, calib_.f_px * calib_.baseline_m / params_.max_depth_m);
  for (const StereoMatch& m : out.stereo) {
    if (!(m.d_px >= min_d)) continue;
    StereoPoint sp;
    if (!stereoObservation(calib_, disp, m.u_px, m.v_px, m.d_px, m.sigma_d_px,
                           params_.match_sigma_px, sp))
      continue;
    if (!sp.p_cam.allFinite() || !sp.cov.allFinite()) continue;  // the dense path too
    TrackPoint tp;
    tp.u_px = m.u_px;
    tp.v_px = m.v_px;
    tp.p_cam = sp.p_cam;
    tp.cov = sp.cov;
    tp.d_px = m.d_px;
    tp.sigma_d_px = m.sigma_d_px;
    out.points.push_back(tp);
  }
}

Status StereoStage::clusterPoints(const StereoStageOutput& out) {
  cluster_pts_.clear();
  cluster_quality_.clear();
  for (const TrackPoint& p : out.points) {
    cluster_pts_.push_back(p.p_cam);
    cluster_quality_.push_back(static_cast<float>(std::sqrt(p.cov.trace())));
  }
  return clusterer_->process(cluster_pts_, cluster_quality_, cur_clusters_);
}

void StereoStage::applyRois(const Eigen::Isometry3d& T_cur_prev, StereoStageOutput& out) {
  if (!clusterer_->project(prev_clusters_, T_cur_prev, calib_, roi_)) return;
  if (roi_.rois.empty()) return;
  out.has_rois = true;
  out.rois = static_cast<int>(roi_.rois.size());
  const float thr_roi = static_cast<float>(params_.corners.threshold_rel) *
                        (params_.detector == PointDetector::kOrb ? 0.0f : out.max_response);
  std::vector<Eigen::Vector2f>& px = out.corner_px;
  std::vector<float>& resp = out.corner_resp;
  // Keep: corners inside a left ROI that reach the normal threshold (disparity bounded by the
  // union of the right ROIs of the ROIs holding it), and corners of unknown cells (full range).
  std::size_t w = 0;
  ranges_.clear();
  for (std::size_t i = 0; i < px.size(); ++i) {
    const Eigen::Vector2f p = px[i];
    int d0 = 1 << 30, d1 = -(1 << 30);
    bool in_roi = false;
    for (const ClusterRoi& r : roi_.rois) {
      if (!r.left.contains(p.x(), p.y())) continue;
      in_roi = true;
      if (r.right.empty()) continue;
      // Right patch centre x - d inside [right.x0, right.x1).
      d0 = std::min(d0, static_cast<int>(std::floor(p.x())) - r.right.x1 + 1);
      d1 = std::max(d1, static_cast<int>(std::ceil(p.x())) - r.right.x0);
    }
    const bool unknown = roi_.isUnknown(p.x(), p.y());
    if (in_roi && resp[i] >= thr_roi) {
      // A point of an unknown cell can also sit in a ROI corner region: full range then.
      ranges_.emplace_back(unknown ? 0 : d0 - 1, unknown ? (1 << 30) : d1 + 1);
    } else if (unknown) {
      ranges_.emplace_back(0, 1 << 30);
      ++out.unknown_corners;
    } else {
      ++out.roi_dropped;
      continue;
    }
    px[w] = p;
    resp[w] = resp[i];
    ++w;
  }
  px.resize(w);
  resp.resize(w);
  // Temporal matching: each previous point is searched inside its cluster's left ROI.
  out.prev_regions.assign(prev_points_, Eigen::Vector4i(0, 0, 0, 0));  // no restriction
  for (const ClusterRoi& r : roi_.rois) {
    if (r.whole_image) continue;
    for (const int m : prev_clusters_[static_cast<std::size_t>(r.cluster)].members)
      out.prev_regions[static_cast<std::size_t>(m)] =
          Eigen::Vector4i(r.left.x0, r.left.y0, r.left.x1, r.left.y1);
  }
}

}  // namespace svslam
