#include "features/corner_detector.hpp"

#include <algorithm>
#include <cmath>

#include "simd/float_row_kernels.hpp"

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

// Taps of the largest kernel: radius ceil(3 sigma) with sigma <= 10 px (CornerParams::validate).
constexpr int kMaxTaps = 64;

// Separable convolution with replicated borders: horizontal kernel kx, then vertical ky,
//   tmp(x, y) = sum_k kx[k + rx] in(x - k, y),   out(x, y) = sum_k ky[k + ry] tmp(x, y - k),
// coordinates clamped to the image, each output summed in tap order (simd::FloatRowKernels::
// convolve); `row` is scratch space of at least w + 2 rx floats. Rows [y0, y1) of one pass.
template <class T>
void horizontalRows(ImageView<const T> in, const std::vector<float>& kx, ImageF32& tmp,
                    std::vector<float>& row, int y0, int y1) {
  const int w = in.width;
  const int rx = static_cast<int>(kx.size() / 2);
  row.resize(static_cast<std::size_t>(w + 2 * rx));
  const simd::FloatRowKernels& k = simd::floatRowKernels();
  const float* taps[kMaxTaps];
  for (int y = y0; y < y1; ++y) {
    const T* src = in.row(y);
    float* pad = row.data();  // pad[i] = in(clamp(i - rx), y)
    for (int i = 0; i < rx; ++i) pad[i] = static_cast<float>(src[0]);
    for (int x = 0; x < w; ++x) pad[x + rx] = static_cast<float>(src[x]);
    for (int i = 0; i < rx; ++i) pad[w + rx + i] = static_cast<float>(src[w - 1]);
    for (int j = 0; j <= 2 * rx; ++j) taps[j] = pad + 2 * rx - j;  // tap j - rx: pad + rx - (j - rx)
    k.convolve(taps, kx.data(), 2 * rx + 1, tmp.row(y), w);
  }
}

void verticalRows(const ImageF32& tmp, const std::vector<float>& ky, ImageF32& out, int y0,
                  int y1) {
  const int h = tmp.height();
  const int ry = static_cast<int>(ky.size() / 2);
  const simd::FloatRowKernels& k = simd::floatRowKernels();
  const float* taps[kMaxTaps];
  for (int y = y0; y < y1; ++y) {
    for (int j = 0; j <= 2 * ry; ++j) taps[j] = tmp.row(std::clamp(y - (j - ry), 0, h - 1));
    k.convolve(taps, ky.data(), 2 * ry + 1, out.row(y), tmp.width());
  }
}

// Rows of stripe i of n over h rows.
inline int stripeBegin(int i, int n, int h) { return static_cast<int>(static_cast<long>(h) * i / n); }

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

template <class T>
void CornerDetector::convolve(ImageView<const T> in, const std::vector<float>& kx,
                              const std::vector<float>& ky, ImageF32& out, Executor& executor) {
  const int n = static_cast<int>(rows_.size());
  const int h = in.height;
  executor.parallelFor(n, [&](int i) {
    horizontalRows(in, kx, tmp_, rows_[static_cast<std::size_t>(i)], stripeBegin(i, n, h),
                   stripeBegin(i + 1, n, h));
  });
  executor.parallelFor(n, [&](int i) {
    verticalRows(tmp_, ky, out, stripeBegin(i, n, h), stripeBegin(i + 1, n, h));
  });
}

Status CornerDetector::process(ImageView<const std::uint8_t> image, std::vector<Corner>& out) {
  SerialExecutor serial;
  return process(image, out, serial);
}

Status CornerDetector::process(ImageView<const std::uint8_t> image, std::vector<Corner>& out,
                               Executor& executor) {
  out.clear();
  if (!init_status_) return init_status_;
  if (image.width != width_ || image.height != height_)
    return Status::invalidArgument("corner detector built for another image size");
  // Row stripes: a few per worker; one with a serial executor.
  const int n = executor.concurrency() > 1 ? std::min(4 * executor.concurrency(), height_) : 1;
  if (static_cast<int>(rows_.size()) != n) rows_.resize(static_cast<std::size_t>(n));
  stripe_max_.assign(static_cast<std::size_t>(n), 0.0f);
  // Gradients (derivative of Gaussian along one axis, Gaussian along the other).
  convolve<std::uint8_t>(image, kd_, kg_, ix_, executor);
  convolve<std::uint8_t>(image, kg_, kd_, iy_, executor);
  executor.parallelFor(n, [&](int i) {
  for (int y = stripeBegin(i, n, height_); y < stripeBegin(i + 1, n, height_); ++y) {
    const float* gx = ix_.row(y);
    const float* gy = iy_.row(y);
    float* xx = ixx_.row(y);
    float* yy = iyy_.row(y);
    float* xy = ixy_.row(y);
    simd::floatRowKernels().products(gx, gy, xx, yy, xy, width_);
  }
  });
  convolve<float>(ixx_.cview(), ki_, ki_, ixx_, executor);
  convolve<float>(iyy_.cview(), ki_, ki_, iyy_, executor);
  convolve<float>(ixy_.cview(), ki_, ki_, ixy_, executor);
  const bool harris = params_.response == CornerResponse::kHarris;
  const double k = params_.harris_k;
  executor.parallelFor(n, [&](int i) {
  float max_r = 0;
  for (int y = stripeBegin(i, n, height_); y < stripeBegin(i + 1, n, height_); ++y) {
    const float* ra = ixx_.row(y);
    const float* rb = ixy_.row(y);
    const float* rc = iyy_.row(y);
    max_r = simd::floatRowKernels().response(ra, rb, rc, harris, k, resp_.row(y), width_, max_r);
  }
  stripe_max_[static_cast<std::size_t>(i)] = max_r;
  });
  float max_r = 0;  // max is exact: the same for any stripes
  for (float m : stripe_max_) max_r = std::max(max_r, m);
  max_response_ = max_r;
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
    // Ties keep raster order (the order of insertion), as a stable sort would, without its buffer.
    std::sort(cell.begin(), cell.end(), [](const Corner& a, const Corner& c) {
      if (a.response != c.response) return a.response > c.response;
      return a.y_px != c.y_px ? a.y_px < c.y_px : a.x_px < c.x_px;
    });
    const std::size_t keep = std::min(cell.size(), static_cast<std::size_t>(params_.max_per_cell));
    out.insert(out.end(), cell.begin(), cell.begin() + static_cast<std::ptrdiff_t>(keep));
  }
  return Status::ok();
}

}  // namespace svslam
