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

// The order of the output within a cell: stronger first, equal responses in raster order of
// the refined position (a strict weak order; fully equal corners are interchangeable).
bool strongerFirst(const Corner& a, const Corner& c) {
  if (a.response != c.response) return a.response > c.response;
  return a.y_px != c.y_px ? a.y_px < c.y_px : a.x_px < c.x_px;
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
  resp_.resize(width, height);
  maxima_x_.resize(static_cast<std::size_t>(width));
  stripes_.emplace_back(width, kd_, kg_, ki_);
  cells_.resize(static_cast<std::size_t>(params_.grid_cols * params_.grid_rows));
  for (auto& cell : cells_) cell.reserve(static_cast<std::size_t>(params_.max_per_cell));
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
  // Row stripes: two per worker (each recomputes a halo of ri + rd rows); one when serial.
  const int n = executor.concurrency() > 1 ? std::min(2 * executor.concurrency(), height_) : 1;
  while (static_cast<int>(stripes_.size()) < n) stripes_.emplace_back(width_, kd_, kg_, ki_);
  stripe_max_.assign(static_cast<std::size_t>(n), 0.0f);
  const bool harris = params_.response == CornerResponse::kHarris;
  executor.parallelFor(n, [&](int i) {
    stripe_max_[static_cast<std::size_t>(i)] = stripes_[static_cast<std::size_t>(i)].process(
        image, harris, params_.harris_k, stripeBegin(i, n, height_), stripeBegin(i + 1, n, height_),
        resp_);
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
  const simd::FloatRowKernels& kern = simd::floatRowKernels();
  for (int y = b; y < height_ - b; ++y) {
    const float* row = resp_.row(y);
    const float* up = resp_.row(y - 1);
    const float* down = resp_.row(y + 1);
    const int count = kern.localMaxima(up, row, down, thr, b, width_ - b, maxima_x_.data());
    for (int i = 0; i < count; ++i) {
      const int x = maxima_x_[static_cast<std::size_t>(i)];
      // Sub-pixel: parabola through the response in x and in y.
      auto offset = [](float m, float c0, float p) {
        const float den = m - 2 * c0 + p;
        return den < 0 ? std::clamp(0.5f * (m - p) / den, -0.5f, 0.5f) : 0.0f;
      };
      const float r = row[x];
      Corner cn;
      cn.x_px = static_cast<float>(x) + offset(row[x - 1], r, row[x + 1]);
      cn.y_px = static_cast<float>(y) + offset(up[x], r, down[x]);
      cn.response = r;
      const int cx = std::min(params_.grid_cols - 1, x * params_.grid_cols / width_);
      const int cy = std::min(params_.grid_rows - 1, y * params_.grid_rows / height_);
      // Each cell keeps its max_per_cell best so far in a heap whose top is the worst of them
      // (capacity reserved in the constructor: no allocation, whatever the image).
      std::vector<Corner>& cell = cells[static_cast<std::size_t>(cy * params_.grid_cols + cx)];
      if (cell.size() < static_cast<std::size_t>(params_.max_per_cell)) {
        cell.push_back(cn);
        std::push_heap(cell.begin(), cell.end(), strongerFirst);
      } else if (strongerFirst(cn, cell.front())) {
        std::pop_heap(cell.begin(), cell.end(), strongerFirst);
        cell.back() = cn;
        std::push_heap(cell.begin(), cell.end(), strongerFirst);
      }
    }
  }
  for (auto& cell : cells) {
    std::sort_heap(cell.begin(), cell.end(), strongerFirst);  // strongest first
    out.insert(out.end(), cell.begin(), cell.end());
  }
  return Status::ok();
}

}  // namespace svslam
