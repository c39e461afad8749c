#include "map/dem_fuser.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "slam/pose_jacobians.hpp"

namespace svslam::map {

namespace {
constexpr float kMinVarIndep = 1e-10f;  // m^2: a sigma_d of 0 would give an infinite weight
constexpr float kInf = std::numeric_limits<float>::infinity();

// floor() as an int without a libm call; precondition |v| < 2^31.
inline std::int32_t floorToInt(float v) {
  const auto i = static_cast<std::int32_t>(v);  // truncates towards zero
  return i - (v < static_cast<float>(i) ? 1 : 0);
}

}  // namespace

const char* toString(DemSkip s) {
  switch (s) {
    case DemSkip::kNone:
      return "none";
    case DemSkip::kPoseNotFinite:
      return "pose not finite";
    case DemSkip::kCovarianceNotFinite:
      return "pose covariance not finite";
    case DemSkip::kNoDisparity:
      return "no dense disparity";
  }
  return "?";
}

DemFuser::DemFuser(const DemParams& params, const StereoCalibration& calib,
                   const Eigen::Matrix3d& R_map_world)
    : params_(params), calib_(calib), R_map_world_(R_map_world) {
  init_status_ = params_.validate();
  if (init_status_.isOk()) init_status_ = calib_.validate();
  if (init_status_.isOk() &&
      (!R_map_world_.allFinite() ||
       (R_map_world_.transpose() * R_map_world_ - Eigen::Matrix3d::Identity()).norm() > 1e-6))
    init_status_ = Status::invalidArgument("map: R_map_world is not a rotation");
  if (init_status_.isOk())
    points_.resize(static_cast<std::size_t>(calib_.width) *
                   static_cast<std::size_t>(calib_.height));
}

void DemFuser::computePoints(const DemFrame& in, DemFuseStats& out) {
  const Eigen::Matrix3d R_map_cam = R_map_world_ * in.T_world_cam.linear();
  const Eigen::Vector3d t_map = R_map_world_ * in.T_world_cam.translation();
  // Pose part of the height variance as a quadratic form in X_cam (see the header):
  // J_theta = q x u = M q with M = -[u]x, q = R_world_cam X_cam.
  const Eigen::Vector3d u = R_map_world_.row(2).transpose();
  const Eigen::Matrix3d R = in.T_world_cam.linear();
  const Eigen::Matrix3d M = -hatSO3(u);
  const Eigen::Matrix3d A = in.pose_cov.topLeftCorner<3, 3>();
  const Eigen::Matrix3d B = in.pose_cov.topRightCorner<3, 3>();
  const Eigen::Matrix3d C = in.pose_cov.bottomRightCorner<3, 3>();
  const Eigen::Matrix3d Q = R.transpose() * M.transpose() * A * M * R;
  const Eigen::Vector3d l = 2.0 * R.transpose() * M.transpose() * B * u;
  const auto c0 = static_cast<float>(u.dot(C * u));

  // Per row v, with w = (x - cx, v - cy, f) and X_cam = s w, s = b / d:
  //   p_map = s (R_map_cam w) + t = s (c0 xu + a_v) + t,  xu = x - cx;
  //   |X|^2 = s^2 (xu^2 + k_v);
  //   var_pose = s^2 (w' Q w) + s (l . w) + c = s^2 (Q00 xu^2 + qb_v xu + qc_v) + s (l0 xu + lr_v)
  //   + c.
  const Eigen::Vector3f col0 = R_map_cam.col(0).cast<float>();
  const Eigen::Vector3f tf = t_map.cast<float>();
  const auto cx = static_cast<float>(calib_.cx_px), b = static_cast<float>(calib_.baseline_m);
  const float inv_cell = static_cast<float>(1.0 / params_.cell_m);
  const float min_d = static_cast<float>(params_.min_disparity_px);
  const float max_range2 = static_cast<float>(params_.max_range_m * params_.max_range_m);
  const auto max_dz = static_cast<float>(params_.max_height_above_camera_m);
  const DisparityResult& disp = *in.disparity;
  int n = 0;
  int i0 = std::numeric_limits<int>::max(), j0 = i0, i1 = std::numeric_limits<int>::min(), j1 = i1;
  for (int v = 0; v < calib_.height; ++v) {
    const float* d_row = disp.disparity_px.row(v);
    const float* s_row = disp.sigma_d_px.row(v);
    const std::uint8_t* g_row = in.left.row(v);
    const double yv = static_cast<double>(v) - calib_.cy_px;
    const Eigen::Vector3d a_d = R_map_cam.col(1) * yv + R_map_cam.col(2) * calib_.f_px;
    const Eigen::Vector3f a = a_d.cast<float>();
    const auto k = static_cast<float>(yv * yv + calib_.f_px * calib_.f_px);
    const auto q2 = static_cast<float>(Q(0, 0));
    const auto q1 = static_cast<float>(2.0 * (Q(0, 1) * yv + Q(0, 2) * calib_.f_px));
    const auto q0 = static_cast<float>(Q(1, 1) * yv * yv + 2.0 * Q(1, 2) * yv * calib_.f_px +
                                       Q(2, 2) * calib_.f_px * calib_.f_px);
    const auto l1 = static_cast<float>(l(0));
    const auto l0 = static_cast<float>(l(1) * yv + l(2) * calib_.f_px);
    for (int x = 0; x < calib_.width; ++x) {
      const float d = d_row[x];
      if (!(d >= min_d)) {  // invalid (+inf is >= min_d: caught below), NaN, or too small
        if (std::isnan(d))
          ++out.points_not_finite;
        else if (d < min_d)
          ++out.points_out_of_range;
        continue;
      }
      const float sd = s_row[x];
      if (!(d < kInf) || !(sd < kInf)) {  // +inf disparity: no match (not counted)
        if (d < kInf) ++out.points_not_finite;
        continue;
      }
      const float s = b / d;
      const float xu = static_cast<float>(x) - cx;
      if (s * s * (xu * xu + k) > max_range2) {
        ++out.points_out_of_range;
        continue;
      }
      const float px = s * (col0.x() * xu + a.x()) + tf.x();
      const float py = s * (col0.y() * xu + a.y()) + tf.y();
      const float dz = s * (col0.z() * xu + a.z());  // r_z . X_cam
      if (dz > max_dz) {
        ++out.points_out_of_range;
        continue;
      }
      const float r = dz / d;
      const float var_indep = std::max(kMinVarIndep, r * r * sd * sd);
      const float var_pose =
          std::max(0.0f, s * s * ((q2 * xu + q1) * xu + q0) + s * (l1 * xu + l0) + c0);
      const float fi = px * inv_cell, fj = py * inv_cell;
      if (!(std::fabs(fi) < 1e9f) || !(std::fabs(fj) < 1e9f) || !(sd >= 0.0f)) {
        ++out.points_not_finite;
        continue;
      }
      Point& pt = points_[static_cast<std::size_t>(n++)];
      pt.i = floorToInt(fi);
      pt.j = floorToInt(fj);
      pt.h_m = dz + tf.z();
      pt.var_indep = var_indep;
      pt.var_pose = var_pose;
      pt.luminance = g_row[x];
      i0 = std::min(i0, pt.i);
      i1 = std::max(i1, pt.i);
      j0 = std::min(j0, pt.j);
      j1 = std::max(j1, pt.j);
    }
  }
  num_points_ = n;
  bi0_ = i0;
  bj0_ = j0;
  bcols_ = n > 0 ? i1 - i0 + 1 : 0;
  brows_ = n > 0 ? j1 - j0 + 1 : 0;
}

void DemFuser::prepareScratch(const DemMap& map) {
  const std::size_t cells = static_cast<std::size_t>(bcols_) * static_cast<std::size_t>(brows_);
  // Grows to twice the need when too small: the footprint of a steady flight varies far less,
  // so only the first frame allocates.
  if (scratch_.size() < cells) scratch_.resize(2 * cells);
  std::fill_n(scratch_.begin(), cells, Accumulator{});
  // The map's current estimate of the box's cells, tile by tile.
  const int n = map.tileCells();
  const int ti0 = map.tileOf(bi0_), ti1 = map.tileOf(bi0_ + bcols_ - 1);
  const int tj0 = map.tileOf(bj0_), tj1 = map.tileOf(bj0_ + brows_ - 1);
  for (int tj = tj0; tj <= tj1; ++tj) {
    for (int ti = ti0; ti <= ti1; ++ti) {
      const DemTile* t = map.tile(ti, tj);
      if (t == nullptr) continue;
      const int ci0 = std::max(bi0_, ti * n), ci1 = std::min(bi0_ + bcols_, (ti + 1) * n);
      const int cj0 = std::max(bj0_, tj * n), cj1 = std::min(bj0_ + brows_, (tj + 1) * n);
      for (int j = cj0; j < cj1; ++j) {
        const DemCell* row = t->cells.data() + static_cast<std::ptrdiff_t>(j - tj * n) * n;
        Accumulator* acc = scratch_.data() + static_cast<std::ptrdiff_t>(j - bj0_) * bcols_;
        for (int i = ci0; i < ci1; ++i) {
          const DemCell& c = row[i - ti * n];
          if (c.count == 0) continue;
          acc[i - bi0_].ref_h = c.height_m;
          acc[i - bi0_].ref_var = map.variance(c);
        }
      }
    }
  }
}

Status DemFuser::process(const DemFrame& in, DemMap& map, DemFuseStats& out) {
  out = DemFuseStats{};
  if (!init_status_.isOk()) return init_status_;
  if (!map.initStatus().isOk()) return map.initStatus();
  if (map.params().cell_m != params_.cell_m || map.tileCells() != params_.tile_cells)
    return Status::invalidArgument("map: the map and the fuser have different grids");
  if (in.disparity == nullptr || in.disparity->disparity_px.empty()) {
    out.skipped = DemSkip::kNoDisparity;
    return Status::ok();
  }
  const auto& d = in.disparity->disparity_px;
  if (d.width() != calib_.width || d.height() != calib_.height ||
      in.disparity->sigma_d_px.width() != calib_.width ||
      in.disparity->sigma_d_px.height() != calib_.height || in.left.width != calib_.width ||
      in.left.height != calib_.height)
    return Status::invalidArgument("map: image or disparity size differs from the calibration");
  if (!in.T_world_cam.matrix().allFinite()) {
    out.skipped = DemSkip::kPoseNotFinite;
    return Status::ok();
  }
  if (!in.pose_cov.allFinite()) {
    out.skipped = DemSkip::kCovarianceNotFinite;
    return Status::ok();
  }
  computePoints(in, out);
  if (num_points_ == 0) return Status::ok();
  prepareScratch(map);
  const auto gate = static_cast<float>(params_.gate_chi2);
  for (int k = 0; k < num_points_; ++k) {
    const Point& p = points_[static_cast<std::size_t>(k)];
    Accumulator& a = scratch_[static_cast<std::size_t>(p.j - bj0_) * bcols_ + (p.i - bi0_)];
    float var = p.var_indep;
    if (a.ref_var >= 0.0f) {
      const float r = p.h_m - a.ref_h;
      const float s = var + p.var_pose + a.ref_var;
      if (r * r > gate * s) {  // sit on the gate: r^2 / (var' + rest) = gate
        var += r * r / gate - s;
        ++out.points_gated;
        ++a.m.gated;
      }
    }
    const double w = 1.0 / var;
    a.m.sum_w += w;
    a.m.sum_wh += w * p.h_m;
    a.m.sum_var_pose += p.var_pose;
    a.m.count += 1;
    a.m.sum_luminance += p.luminance;
  }
  // Each frame cell into the map, tile by tile (one tile lookup per tile, not per cell).
  const std::int64_t seq = seq_++;
  out.seq = seq;
  const int n = map.tileCells();
  const int ti0 = map.tileOf(bi0_), ti1 = map.tileOf(bi0_ + bcols_ - 1);
  const int tj0 = map.tileOf(bj0_), tj1 = map.tileOf(bj0_ + brows_ - 1);
  for (int tj = tj0; tj <= tj1; ++tj) {
    for (int ti = ti0; ti <= ti1; ++ti) {
      const int ci0 = std::max(bi0_, ti * n), ci1 = std::min(bi0_ + bcols_, (ti + 1) * n);
      const int cj0 = std::max(bj0_, tj * n), cj1 = std::min(bj0_ + brows_, (tj + 1) * n);
      DemTile* t = nullptr;
      bool refused = false;
      for (int j = cj0; j < cj1; ++j) {
        const Accumulator* acc = scratch_.data() + static_cast<std::ptrdiff_t>(j - bj0_) * bcols_;
        for (int i = ci0; i < ci1; ++i) {
          const CellMeasurement& m = acc[i - bi0_].m;
          if (m.count == 0) continue;
          if (t == nullptr && !refused) {
            t = map.tileForWrite(ti, tj);
            refused = t == nullptr;
          }
          if (refused) {
            out.points_no_tile += static_cast<int>(m.count);
            continue;
          }
          const auto k = static_cast<std::size_t>((j - tj * n) * n + (i - ti * n));
          DemMap::fuseCell(t->cells[k], m, params_.reject_variance_factor);
          DemMap::recordSource(*t, k, seq);
          ++out.cells_updated;
          out.points_fused += static_cast<int>(m.count);
        }
      }
      if (t != nullptr) DemMap::touch(*t, seq, in.t_ns);
    }
  }
  return Status::ok();
}

}  // namespace svslam::map
