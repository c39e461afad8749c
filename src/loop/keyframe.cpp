#include "loop/keyframe.hpp"

#include <algorithm>
#include <cmath>

#include "odometry/stereo_stage.hpp"

namespace svslam {

StereoPoint Keyframe::point(std::size_t i) const {
  return reprojectPixel(calib, uv_px[i].x(), uv_px[i].y(), disparity_px[i], sigma_d_px[i],
                        matching_error_px);
}

std::size_t Keyframe::bytes() const {
  return sizeof(Keyframe) + descriptors.capacity() * sizeof(OrbDescriptor) +
         uv_px.capacity() * sizeof(Eigen::Vector2f) + disparity_px.capacity() * sizeof(float) +
         sigma_d_px.capacity() * sizeof(float) + bow.capacity() * sizeof(bow[0]);
}

OrbParams KeyframeParams::defaultOrb() {
  OrbParams p;
  p.grid_cols = 8;
  p.grid_rows = 6;
  p.max_per_cell = 16;
  p.fast_threshold = 15;
  return p;
}

Status KeyframeParams::validate() const {
  if (!(travel_depth_fraction > 0) || !std::isfinite(travel_depth_fraction))
    return Status::invalidArgument("loop.keyframe travel_depth_fraction must be > 0");
  if (!(min_travel_m >= 0) || !std::isfinite(min_travel_m))
    return Status::invalidArgument("loop.keyframe min_travel_m must be >= 0");
  if (!(min_rotation_deg > 0 && min_rotation_deg <= 180))
    return Status::invalidArgument("loop.keyframe min_rotation_deg must be in (0, 180]");
  if (max_points < 16 || max_points > 2000)
    return Status::invalidArgument("loop.keyframe max_points must be in 16..2000");
  if (!(max_point_sigma_m > 0) || !std::isfinite(max_point_sigma_m))
    return Status::invalidArgument("loop.keyframe max_point_sigma_m must be > 0");
  if (!(matching_error_px > 0) || !std::isfinite(matching_error_px))
    return Status::invalidArgument("loop.keyframe matching_error_px must be > 0");
  return orb.validate();
}

bool KeyframeSelector::isKeyframe(const Eigen::Isometry3d& T_world_cam) const {
  if (!has_last_) return true;
  const Eigen::Isometry3d T_last_cam = T_world_last_.inverse() * T_world_cam;
  const double travel_m = T_last_cam.translation().norm();
  const double angle_deg =
      Eigen::AngleAxisd(T_last_cam.linear()).angle() * 180.0 / 3.14159265358979323846;
  const double need_m = std::max(params_.min_travel_m, params_.travel_depth_fraction * median_depth_m_);
  return travel_m >= need_m || angle_deg >= params_.min_rotation_deg;
}

void KeyframeSelector::accept(const Eigen::Isometry3d& T_world_cam, double median_depth_m) {
  has_last_ = true;
  T_world_last_ = T_world_cam;
  median_depth_m_ = median_depth_m;
}

KeyframeBuilder::KeyframeBuilder(const KeyframeParams& params, const StereoCalibration& calib)
    : params_(params), calib_(calib) {
  init_status_ = params.validate();
  if (init_status_) init_status_ = calib.validate();
  if (!init_status_) return;
  orb_ = std::make_unique<OrbExtractor>(params.orb, calib.width, calib.height);
  init_status_ = orb_->initStatus();
  const std::size_t cap =
      static_cast<std::size_t>(params.orb.grid_cols * params.orb.grid_rows * params.orb.max_per_cell);
  kp_.reserve(cap);
  desc_.reserve(cap);
  order_.reserve(cap);
  depths_.reserve(cap);
}

// The keypoint's own sub-pixel position with the disparity and sigma bilinearly interpolated
// from its 4 neighbouring pixels (all valid, disparities within 1 px of each other: not across
// a depth edge), reprojected with the keypoint's matching error.
bool KeyframeBuilder::subpixelPoint(const DisparityResult& dense, float u_px, float v_px,
                                    float& d_px, float& sigma_d_px, StereoPoint& out) const {
  const int x0 = static_cast<int>(std::floor(u_px)), y0 = static_cast<int>(std::floor(v_px));
  if (x0 < 0 || y0 < 0 || x0 + 1 >= dense.disparity_px.width() ||
      y0 + 1 >= dense.disparity_px.height())
    return false;
  const float ax = u_px - static_cast<float>(x0), ay = v_px - static_cast<float>(y0);
  float d[4], s[4];
  for (int i = 0; i < 4; ++i) {
    d[i] = dense.disparity_px(x0 + (i & 1), y0 + (i >> 1));
    s[i] = dense.sigma_d_px(x0 + (i & 1), y0 + (i >> 1));
    if (!std::isfinite(d[i]) || !std::isfinite(s[i]) || !(d[i] > 0.0f)) return false;
  }
  const float lo = std::min({d[0], d[1], d[2], d[3]}), hi = std::max({d[0], d[1], d[2], d[3]});
  if (hi - lo > 1.0f) return false;
  const float w[4] = {(1 - ax) * (1 - ay), ax * (1 - ay), (1 - ax) * ay, ax * ay};
  float dd = 0, ss = 0;
  for (int i = 0; i < 4; ++i) {
    dd += w[i] * d[i];
    ss += w[i] * s[i];
  }
  d_px = dd;
  sigma_d_px = ss;
  out = reprojectPixel(calib_, u_px, v_px, dd, ss, params_.matching_error_px);
  return out.p_cam.allFinite() && out.cov.allFinite();
}

Status KeyframeBuilder::process(ImageView<const std::uint8_t> left, const DisparityResult& dense,
                                Keyframe& out) {
  if (!init_status_) return init_status_;
  if (left.width != calib_.width || left.height != calib_.height ||
      dense.disparity_px.width() != calib_.width || dense.disparity_px.height() != calib_.height)
    return Status::invalidArgument("keyframe: image or disparity size differs from the calibration");
  if (Status s = orb_->process(left, kp_, desc_); !s) return s;
  // Round-robin over the ORB cells: the r-th strongest of every cell before any (r+1)-th.
  const int cols = params_.orb.grid_cols, rows = params_.orb.grid_rows;
  std::vector<int>& order = order_;
  order.clear();
  {
    // kp_ is cell by cell, strongest first: rank within the cell.
    std::vector<std::pair<int, int>> rank_index;  // small (<= cells * max_per_cell)
    rank_index.reserve(kp_.size());
    int prev_cell = -1, rank = 0;
    for (std::size_t i = 0; i < kp_.size(); ++i) {
      const int cx = std::clamp(static_cast<int>(std::floor(kp_[i].x_px * cols / calib_.width)), 0,
                                cols - 1);
      const int cy = std::clamp(static_cast<int>(std::floor(kp_[i].y_px * rows / calib_.height)),
                                0, rows - 1);
      const int cell = cy * cols + cx;
      rank = cell == prev_cell ? rank + 1 : 0;
      prev_cell = cell;
      rank_index.emplace_back(rank, static_cast<int>(i));
    }
    std::stable_sort(rank_index.begin(), rank_index.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    for (const auto& ri : rank_index) order.push_back(ri.second);
  }
  out.descriptors.clear();
  out.uv_px.clear();
  out.disparity_px.clear();
  out.sigma_d_px.clear();
  out.calib = calib_;
  out.matching_error_px = params_.matching_error_px;
  out.bow.clear();
  depths_.clear();
  const std::size_t max_points = static_cast<std::size_t>(params_.max_points);
  out.descriptors.reserve(max_points);
  out.uv_px.reserve(max_points);
  out.disparity_px.reserve(max_points);
  out.sigma_d_px.reserve(max_points);
  for (int i : order) {
    if (out.descriptors.size() >= max_points) break;
    const OrbKeypoint& k = kp_[static_cast<std::size_t>(i)];
    StereoPoint p;
    float d_px = 0, sigma_d_px = 0;
    if (!subpixelPoint(dense, k.x_px, k.y_px, d_px, sigma_d_px, p)) continue;
    if (!p.p_cam.allFinite() || !p.cov.allFinite() || !(p.p_cam.z() > 0)) continue;
    if (std::sqrt(p.cov.trace()) > params_.max_point_sigma_m) continue;
    out.descriptors.push_back(desc_[static_cast<std::size_t>(i)]);
    out.uv_px.emplace_back(k.x_px, k.y_px);
    out.disparity_px.push_back(d_px);
    out.sigma_d_px.push_back(sigma_d_px);
    depths_.push_back(static_cast<float>(p.p_cam.z()));
  }
  if (out.descriptors.size() < 16)
    return Status::failedPrecondition("keyframe: fewer than 16 ORB points with a valid disparity");
  auto mid = depths_.begin() + static_cast<std::ptrdiff_t>(depths_.size() / 2);
  std::nth_element(depths_.begin(), mid, depths_.end());
  out.median_depth_m = *mid;
  return Status::ok();
}

}  // namespace svslam
