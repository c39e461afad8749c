#include "stereo/reprojection.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace svslam {

Status ReprojectionParams::validate() const {
  if (!std::isfinite(sigma_uv_px) || sigma_uv_px < 0.0)
    return Status::invalidArgument("sigma_uv_px must be finite and >= 0");
  if (!std::isfinite(min_disparity_px) || min_disparity_px <= 0.0)
    return Status::invalidArgument("min_disparity_px must be > 0");
  if (!(max_depth_m > 0.0)) return Status::invalidArgument("max_depth_m must be > 0");
  if (step_px < 1) return Status::invalidArgument("step_px must be >= 1");
  return Status::ok();
}

StereoPoint reprojectPixel(const StereoCalibration& calib, double u_px, double v_px, double d_px,
                           double sigma_d_px, double sigma_uv_px) {
  const double b = calib.baseline_m;
  const double f = calib.f_px;
  const double du = u_px - calib.cx_px;
  const double dv = v_px - calib.cy_px;
  const double d_measured_px = d_px;
  d_px += calib.disparity_offset_px;
  StereoPoint p;
  if (d_measured_px > 0.0 && !(d_px > 0.0)) {  // the offset took it to zero or below: no point
    p.p_cam.setConstant(std::numeric_limits<double>::quiet_NaN());
    p.cov.setConstant(std::numeric_limits<double>::quiet_NaN());
    return p;
  }
  p.p_cam = Eigen::Vector3d(du * b / d_px, dv * b / d_px, f * b / d_px);
  Eigen::Matrix3d J;
  const double d2 = d_px * d_px;
  J << b / d_px, 0.0, -du * b / d2,  //
      0.0, b / d_px, -dv * b / d2,   //
      0.0, 0.0, -f * b / d2;
  const Eigen::Vector3d var(sigma_uv_px * sigma_uv_px, sigma_uv_px * sigma_uv_px,
                            sigma_d_px * sigma_d_px);
  p.cov = J * var.asDiagonal() * J.transpose();
  p.u_px = static_cast<float>(u_px);
  p.v_px = static_cast<float>(v_px);
  p.d_px = static_cast<float>(d_px);
  p.sigma_d_px = static_cast<float>(sigma_d_px);
  return p;
}

bool neighbourhoodPoint(ImageView<const float> disparity_px, ImageView<const float> sigma_d_px,
                        const StereoCalibration& calib, double u_px, double v_px,
                        double matching_error_px, int min_valid, StereoPoint& out) {
  const bool half = matching_error_px == 0.5;
  if (!half && matching_error_px != 1.0) return false;
  const int x0 = static_cast<int>(std::lround(u_px));
  const int y0 = static_cast<int>(std::lround(v_px));
  if (x0 < 1 || y0 < 1 || x0 >= disparity_px.width - 1 || y0 >= disparity_px.height - 1)
    return false;
  auto valid = [&](int x, int y) {
    const float d = disparity_px(x, y), s = sigma_d_px(x, y);
    return std::isfinite(d) && std::isfinite(s) && d > 0.0f;
  };
  if (!valid(x0, y0)) return false;
  const StereoPoint c =
      reprojectPixel(calib, x0, y0, disparity_px(x0, y0), sigma_d_px(x0, y0), 0.0);
  Eigen::Vector3d pts[9];
  Eigen::Matrix3d covs[9];
  int n = 0;
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) {
      if (dx == 0 && dy == 0) {
        pts[n] = c.p_cam;
        covs[n++] = c.cov;
        continue;
      }
      if (!valid(x0 + dx, y0 + dy)) continue;
      const StereoPoint q = reprojectPixel(calib, x0 + dx, y0 + dy, disparity_px(x0 + dx, y0 + dy),
                                           sigma_d_px(x0 + dx, y0 + dy), 0.0);
      pts[n] = half ? Eigen::Vector3d(0.5 * (c.p_cam + q.p_cam)) : q.p_cam;
      covs[n++] = half ? Eigen::Matrix3d(0.5 * (c.cov + q.cov)) : q.cov;
    }
  if (n < min_valid) return false;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (int i = 0; i < n; ++i) mean += pts[i];
  mean /= n;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d e = pts[i] - mean;
    cov += covs[i] + e * e.transpose();
  }
  out = c;
  out.p_cam = mean;
  out.cov = cov / n;
  out.u_px = static_cast<float>(u_px);
  out.v_px = static_cast<float>(v_px);
  return true;
}

Status reprojectDisparity(ImageView<const float> disparity_px, ImageView<const float> sigma_d_px,
                          const StereoCalibration& calib, const ReprojectionParams& params,
                          std::vector<StereoPoint>& out) {
  out.clear();
  if (Status s = params.validate(); !s) return s;
  if (Status s = calib.validate(); !s) return s;
  if (disparity_px.width != sigma_d_px.width || disparity_px.height != sigma_d_px.height)
    return Status::invalidArgument("disparity and sigma maps differ in size");
  if (disparity_px.width != calib.width || disparity_px.height != calib.height)
    return Status::invalidArgument("disparity map size differs from the calibration's image size");
  const double min_d =
      std::max(params.min_disparity_px, calib.f_px * calib.baseline_m / params.max_depth_m);
  for (int y = 0; y < disparity_px.height; y += params.step_px) {
    const float* d = disparity_px.row(y);
    const float* s = sigma_d_px.row(y);
    for (int x = 0; x < disparity_px.width; x += params.step_px) {
      if (!std::isfinite(d[x]) || !std::isfinite(s[x]) || d[x] < min_d) continue;
      out.push_back(reprojectPixel(calib, x, y, d[x], s[x], params.sigma_uv_px));
    }
  }
  return Status::ok();
}

}  // namespace svslam
