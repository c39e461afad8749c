#pragma once
// Interest points: precise Harris (Schmid, Mohr & Bauckhage: derivatives of a Gaussian instead
// of a [-1 0 1] mask) and Shi-Tomasi, with grid bucketing so the points cover the image.
//
// Gradients Ix, Iy by convolution with the derivative of a Gaussian (sigma_d_px); the structure
// tensor M = G(sigma_i_px) * [Ix^2 IxIy; IxIy Iy^2]; response
//   Harris:     det M - k (trace M)^2
//   Shi-Tomasi: the smaller eigenvalue of M.
// Local maxima over 3x3 above threshold_rel * (largest response) are kept; the image is cut
// into grid_cols x grid_rows cells and each cell keeps its max_per_cell strongest corners.
// Positions are refined to sub-pixel by fitting a parabola to the response in x and in y.
#include <vector>

#include "core/executor.hpp"
#include "core/image.hpp"
#include "core/status.hpp"
#include "features/corner_response_rows.hpp"

namespace svslam {

enum class CornerResponse { kHarris, kShiTomasi };

struct CornerParams {
  CornerResponse response = CornerResponse::kHarris;
  double sigma_d_px = 1.0;      // derivative-of-Gaussian scale, px, 0.5..5
  double sigma_i_px = 2.0;      // integration scale of the structure tensor, px, 0.5..10
  double harris_k = 0.04;       // Harris constant, 0.01..0.25
  double threshold_rel = 0.01;  // minimum response relative to the image's largest, 0..1
  int grid_cols = 8;            // bucketing grid, >= 1
  int grid_rows = 6;            // >= 1
  int max_per_cell = 20;        // >= 1
  int border_px = 8;            // no corner closer to the image border, >= 1
  Status validate() const;
};

struct Corner {
  float x_px = 0;
  float y_px = 0;
  float response = 0;
};

class CornerDetector {
 public:
  CornerDetector(const CornerParams& params, int width, int height);
  const Status& initStatus() const { return init_status_; }
  // Corners of `image` (width x height), strongest first within each cell, cells row-major.
  Status process(ImageView<const std::uint8_t> image, std::vector<Corner>& out);
  // The same with the filtering and the response computed over row stripes on `executor`
  // (each output value is computed by the same operations whatever the stripe: the corners
  // are identical for any number of stripes).
  Status process(ImageView<const std::uint8_t> image, std::vector<Corner>& out,
                 Executor& executor);
  // Largest response of the last processed image (0 for a flat one).
  float lastMaxResponse() const { return max_response_; }

 private:
  CornerParams params_;
  Status init_status_;
  int width_, height_;
  float max_response_ = 0;
  std::vector<float> kd_, kg_, ki_;  // derivative, smoothing and integration kernels
  ImageF32 resp_;                            // corner response of the last image
  std::vector<CornerResponseRows> stripes_;  // one per row stripe, rings preallocated
  std::vector<int> maxima_x_;                // per row: columns of the local maxima
  std::vector<float> stripe_max_;         // per stripe: largest response
  std::vector<std::vector<Corner>> cells_;  // bucketing grid, capacity kept between frames
};

}  // namespace svslam
