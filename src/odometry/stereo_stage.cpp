#include "odometry/stereo_stage.hpp"

#include <algorithm>

namespace svslam {

namespace {
CornerParams detectorParams(const StereoOdometryParams& p) {
  CornerParams c = p.corners;
  // ROI tracking: the detector runs at the lowered threshold of the unknown cells; the
  // odometry keeps ROI corners only at the normal one (StereoOdometry::applyRois).
  if (p.roi_tracking) c.threshold_rel *= p.unknown_threshold_factor;
  return c;
}
}  // namespace

void StereoStageOutput::clear() {
  has_disparity = false;
  matched = false;
  corner_px.clear();
  corner_resp.clear();
  max_response = 0.0f;
  stereo.clear();
  stereo_stats = StereoMatchStats{};
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
  if (init_status_) corners_.reserve(2048);
  // Points per frame: the detector's bucketing bounds them (cells x kept per cell).
  const bool orb = params.detector == PointDetector::kOrb;
  const int cells = orb ? params.orb.grid_cols * params.orb.grid_rows
                        : params.corners.grid_cols * params.corners.grid_rows;
  const int per_cell = orb ? params.orb.max_per_cell : params.corners.max_per_cell;
  max_points_ = static_cast<std::size_t>(cells) * static_cast<std::size_t>(per_cell);
}

StereoStage::~StereoStage() = default;

Status StereoStage::process(ImageView<const std::uint8_t> left,
                            ImageView<const std::uint8_t> right, StereoStageOutput& out,
                            Executor& executor, StageObserver* observer) {
  if (!init_status_) return init_status_;
  if (left.width != calib_.width || left.height != calib_.height || right.width != calib_.width ||
      right.height != calib_.height)
    return Status::invalidArgument("stereo stage: image size differs from the calibration's");
  out.clear();
  if (dense_) {
    if (Status s = dense_->process(left, right, out.disparity, executor); !s) return s;
    out.has_disparity = true;
    if (observer) observer->stageDone("dense_stereo");
  }
  if (params_.roi_tracking) return Status::ok();
  if (Status s = detect(left, out, executor); !s) return s;
  if (observer) observer->stageDone("detect");
  ImageView<const float> prior;
  if (out.has_disparity) prior = out.disparity.disparity_px.cview();
  if (Status s = match(left, right, prior, nullptr, out); !s) return s;
  out.matched = true;
  if (observer) observer->stageDone("stereo_match");
  return Status::ok();
}

Status StereoStage::detect(ImageView<const std::uint8_t> left, StereoStageOutput& out,
                           Executor& executor) {
  if (!init_status_) return init_status_;
  out.corner_px.clear();
  out.corner_resp.clear();
  // A pooled output is sized once for the bound (no growth frame after frame).
  out.corner_px.reserve(max_points_);
  out.corner_resp.reserve(max_points_);
  out.max_response = 0.0f;
  if (orb_) {
    if (Status s = orb_->process(left, orb_kp_, orb_desc_); !s) return s;
    for (const OrbKeypoint& k : orb_kp_) {
      out.corner_px.emplace_back(k.x_px, k.y_px);
      out.corner_resp.push_back(k.score);
    }
    return Status::ok();
  }
  if (Status s = detector_.process(left, corners_, executor); !s) return s;
  for (const Corner& c : corners_) {
    out.corner_px.emplace_back(c.x_px, c.y_px);
    out.corner_resp.push_back(c.response);
  }
  out.max_response = detector_.lastMaxResponse();
  return Status::ok();
}

Status StereoStage::match(ImageView<const std::uint8_t> left, ImageView<const std::uint8_t> right,
                          ImageView<const float> prior,
                          const std::vector<Eigen::Vector2i>* ranges, StereoStageOutput& out) {
  if (!init_status_) return init_status_;
  out.stereo.reserve(std::max(max_points_, out.corner_px.size()));  // at most one per point
  return stereo_matcher_.process(left, right, out.corner_px, prior, out.stereo, out.stereo_stats,
                                 ranges);
}

}  // namespace svslam
