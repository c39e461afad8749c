#include "features/corner_detector.hpp"

#include <algorithm>
#include <cmath>

namespace svslam {
namespace {

std::vector<float> gaussian(double sigma, bool derivative) {
  const int r = std::max(1, static_cast<int>(std::ceil(3.0 * sigma)));
  std::vector<float> k(static_cast<std::size_t>(2 * r + 1));
  double sum = 0;
  for (int i = -r; i <= r; ++i) {
    const double g = std::exp(-0.5 * i * i / (sigma * sigma));
    sum += g;
    k[static_cast<std::size_t>(i + r)] =
        static_cast<float>(derivative ? -i * g / (sigma * sigma) : g);
  }
  for (auto& v : k) v = static_cast<float>(v / sum);
  return k;
}

// Separable convolution with replicated borders: horizontal kernel kx, then vertical ky.
template <class T>
void convolve(ImageView<const T> in, const std::vector<float>& kx, const std::vector<float>& ky,
              ImageF32& tmp, ImageF32& out) {
  const int w = in.width, h = in.height;
  const int rx = static_cast<int>(kx.size() / 2), ry = static_cast<int>(ky.size() / 2);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      float s = 0;
      for (int k = -rx; k <= rx; ++k)
        s += kx[static_cast<std::size_t>(k + rx)] *
             static_cast<float>(in(std::clamp(x - k, 0, w - 1), y));
      tmp(x, y) = s;
    }
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      float s = 0;
      for (int k = -ry; k <= ry; ++k)
        s += ky[static_cast<std::size_t>(k + ry)] * tmp(x, std::clamp(y - k, 0, h - 1));
      out(x, y) = s;
    }
}

}  // namespace

Status CornerParams::validate() const {
  if (!(sigma_d_px >= 0.5 && sigma_d_px <= 5))
    return Status::invalidArgument("sigma_d_px must be in 0.5..5");
  if (!(sigma_i_px >= 0.5 && sigma_i_px <= 10))
    return Status::invalidArgument("sigma_i_px must be in 0.5..10");
  if (!(harris_k >= 0.01 && harris_k <= 0.25))
    return Status::invalidArgument("harris_k must be in 0.01..0.25");
  if (!(threshold_rel >= 0 && threshold_rel <= 1))
    return Status::invalidArgument("threshold_rel must be in 0..1");
  if (grid_cols < 1 || grid_rows < 1 || max_per_cell < 1)
    return Status::invalidArgument("grid and max_per_cell must be >= 1");
  if (border_px < 1) return Status::invalidArgument("border_px must be >= 1");
  return Status::ok();
}

CornerDetector::CornerDetector(const CornerParams& params, int width, int height)
    : params_(params), width_(width), height_(height) {
  init_status_ = params_.validate();
  if (init_status_ && (width < 2 * params_.border_px + 3 || height < 2 * params_.border_px + 3))
    init_status_ = Status::invalidArgument("image too small for the corner detector's border");
  if (!init_status_) return;
  kd_ = gaussian(params_.sigma_d_px, true);
  kg_ = gaussian(params_.sigma_d_px, false);
  ki_ = gaussian(params_.sigma_i_px, false);
  for (ImageF32* im : {&tmp_, &ix_, &iy_, &ixx_, &iyy_, &ixy_, &resp_}) im->resize(width, height);
  cells_.resize(static_cast<std::size_t>(params_.grid_cols * params_.grid_rows));
}

Status CornerDetector::process(ImageView<const std::uint8_t> image, std::vector<Corner>& out) {
  out.clear();
  if (!init_status_) return init_status_;
  if (image.width != width_ || image.height != height_)
    return Status::invalidArgument("corner detector built for another image size");
  // Gradients (derivative of Gaussian along one axis, Gaussian along the other).
  convolve<std::uint8_t>(image, kd_, kg_, tmp_, ix_);
  convolve<std::uint8_t>(image, kg_, kd_, tmp_, iy_);
  for (int y = 0; y < height_; ++y)
    for (int x = 0; x < width_; ++x) {
      ixx_(x, y) = ix_(x, y) * ix_(x, y);
      iyy_(x, y) = iy_(x, y) * iy_(x, y);
      ixy_(x, y) = ix_(x, y) * iy_(x, y);
    }
  convolve<float>(ixx_.cview(), ki_, ki_, tmp_, ixx_);
  convolve<float>(iyy_.cview(), ki_, ki_, tmp_, iyy_);
  convolve<float>(ixy_.cview(), ki_, ki_, tmp_, ixy_);
  float max_r = 0;
  for (int y = 0; y < height_; ++y)
    for (int x = 0; x < width_; ++x) {
      const double a = ixx_(x, y), b = ixy_(x, y), c = iyy_(x, y);
      const double r = params_.response == CornerResponse::kHarris
                           ? a * c - b * b - params_.harris_k * (a + c) * (a + c)
                           : 0.5 * (a + c) - std::sqrt(0.25 * (a - c) * (a - c) + b * b);
      resp_(x, y) = static_cast<float>(r);
      max_r = std::max(max_r, resp_(x, y));
    }
  if (!(max_r > 0)) return Status::ok();  // flat image: no corner
  const float thr = static_cast<float>(params_.threshold_rel) * max_r;
  // Local maxima, bucketed by cell.
  const int b = params_.border_px;
  std::vector<std::vector<Corner>>& cells = cells_;
  for (auto& cell : cells) cell.clear();
  for (int y = b; y < height_ - b; ++y)
    for (int x = b; x < width_ - b; ++x) {
      const float r = resp_(x, y);
      if (r <= thr) continue;
      bool is_max = true;
      for (int dy = -1; dy <= 1 && is_max; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          if (dx == 0 && dy == 0) continue;
          const float q = resp_(x + dx, y + dy);
          if (q > r ||
              (q == r && (dy < 0 || (dy == 0 && dx < 0)))) {  // ties: first in raster order
            is_max = false;
            break;
          }
        }
      if (!is_max) continue;
      // Sub-pixel: parabola through the response in x and in y.
      auto offset = [](float m, float c0, float p) {
        const float den = m - 2 * c0 + p;
        return den < 0 ? std::clamp(0.5f * (m - p) / den, -0.5f, 0.5f) : 0.0f;
      };
      Corner cn;
      cn.x_px = static_cast<float>(x) + offset(resp_(x - 1, y), r, resp_(x + 1, y));
      cn.y_px = static_cast<float>(y) + offset(resp_(x, y - 1), r, resp_(x, y + 1));
      cn.response = r;
      const int cx = std::min(params_.grid_cols - 1, x * params_.grid_cols / width_);
      const int cy = std::min(params_.grid_rows - 1, y * params_.grid_rows / height_);
      cells[static_cast<std::size_t>(cy * params_.grid_cols + cx)].push_back(cn);
    }
  for (auto& cell : cells) {
    std::stable_sort(cell.begin(), cell.end(),
                     [](const Corner& a, const Corner& c) { return a.response > c.response; });
    const std::size_t keep = std::min(cell.size(), static_cast<std::size_t>(params_.max_per_cell));
    out.insert(out.end(), cell.begin(), cell.begin() + static_cast<std::ptrdiff_t>(keep));
  }
  return Status::ok();
}

}  // namespace svslam
