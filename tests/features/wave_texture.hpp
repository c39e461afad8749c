#pragma once
// A continuous band-limited texture for the matcher tests:
//   t(x, y) = 128 + a sum_k sin(w_k . (x, y) + phi_k)
// over k random plane waves with uniform directions, wavelengths log-uniform in
// [lambda_min, lambda_max] (units of x and y) and uniform phases, a = sigma / sqrt(k / 2) so the
// texture's standard deviation is sigma. Seeded: the same seed gives the same texture.
#include <array>
#include <cmath>
#include <random>
#include <vector>

namespace svslam::test_texture {

class WaveTexture {
 public:
  WaveTexture(unsigned seed, double lambda_min, double lambda_max, int k, double sigma) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u01(0, 1);
    for (int i = 0; i < k; ++i) {
      const double th = 2 * M_PI * u01(rng);
      const double lambda = lambda_min * std::pow(lambda_max / lambda_min, u01(rng));
      const double w = 2 * M_PI / lambda;
      waves_.push_back({w * std::cos(th), w * std::sin(th), 2 * M_PI * u01(rng)});
    }
    amp_ = sigma / std::sqrt(0.5 * k);
  }
  double operator()(double x, double y) const {
    double s = 0;
    for (const auto& w : waves_) s += std::sin(w[0] * x + w[1] * y + w[2]);
    return 128.0 + amp_ * s;
  }

 private:
  std::vector<std::array<double, 3>> waves_;
  double amp_ = 1;
};

}  // namespace svslam::test_texture
