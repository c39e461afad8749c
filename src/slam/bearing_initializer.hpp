#pragma once
// Landmark initialisation from bearings alone (seed 003 section 5; seed 000 part 2, "observation
// filter ~ Gaussian particles"), in the plane (D = 2, the seed's setting) and in space (D = 3).
//
// One view: an observer at o (m, world) sees the landmark along the unit direction d with an
// angular error sigma (rad). With r = |x - o| and alpha the angle between x - o and d, seed 003
// eq. (14) gives, per unit area in the plane,
//     p(x) = 1 / ((R_max - R_min) r) * N(alpha; 0, sigma),        R_min <= r <= R_max, else 0:
// the probability of a range interval [R, R + dR] does not depend on R (eqs. 7-13). The same
// argument in space (volume element r^2 dr dOmega) gives, per unit volume,
//     p(x) = 1 / ((R_max - R_min) r^2) * N2(alpha; sigma),   N2 = exp(-alpha^2 / 2 sigma^2) /
// (2 pi sigma^2), the angular error isotropic about d (small angles): in both cases the density
// per unit range along the cone is uniform and its cross-section spreads as r sigma.
// Several views (k >= 2): p = prod_k p_k / integral(prod_k p_k) (Stroupe et al., cited by the
// seed). It is approximated by a Gaussian whose mean and covariance are those of samples drawn
// by the rejection method: a point s uniform in a box around the bearings' intersection and
// nu uniform in [0, 1); s is kept when nu < p(s) / p_max, p_max = p at the intersection (the
// seed's choice). Should a drawn point exceed p_max (the 1/r^(D-1) factors can put the mode a
// little nearer than the intersection), p_max is raised to p(s) and each sample kept so far stays
// with probability p_max_old / p_max_new: the kept samples follow p exactly inside the box.
//
// The box: centred on the intersection x0 (the point nearest to every ray in least squares;
// when that point is not in front of every view within [R_min, R_max] and the bearings are
// within 3 sigma of each other, the densest point of the first bearing, else kOutOfRange),
// its axes the eigenvectors of the linearised covariance C_lin = (sum_k (I - d_k d_k^T) /
// (sigma_k r_k)^2)^-1 (r_k = |x0 - o_k|), half-widths box_sigmas sqrt(eigenvalue), capped at
// R_max; a side whose edge the kept samples reach grows and the pass is repeated (the density
// is skewed toward far ranges at small parallax). Views too parallel (the cones nearly the same, seed 003 figure 17's fourth
// trajectory) are refused before sampling: the largest angle between two bearings must reach
// min_parallax_sigmas times the largest sigma, and x0 must lie in front of every view within
// [R_min, R_max]; the caller waits for a better view. With min_parallax_sigmas = 0 every pair
// of views is sampled, however parallel (figure 17's raw estimate).
//
// Randomness: a 64-bit Mersenne twister seeded from params.seed and the caller's stream number
// (e.g. the track id): the same views, seed and stream give the same Gaussian on every
// platform (the uniform numbers are formed from the raw 64-bit outputs, not by a library
// distribution).
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "core/status.hpp"

namespace svslam {

struct BearingInitParams {
  double r_min_m = 0.5;            // vision range, lower bound, m, > 0
  double r_max_m = 200.0;          // vision range, upper bound, m, > r_min_m
  int num_samples = 500;           // accepted samples the Gaussian is fitted to, [10, 1e6]
  int max_draws = 1000000;         // drawn points before giving up, >= num_samples
  double box_sigmas = 4.0;         // box half-width in linearised sigmas, [2, 20]
  double min_parallax_sigmas = 20;  // views wait until two bearings differ by this many
                                    // sigmas (20: depth error about 7 %; 8: 18 %, a larger
                                    // drift on the camera-loss flights, docs/bearing_only.md)
  std::uint64_t seed = 1;          // random seed (with the caller's stream number)
  Status validate() const;
};

template <int D>
struct BearingView {
  Eigen::Matrix<double, D, 1> origin_m;   // observer position, world, m
  Eigen::Matrix<double, D, 1> direction;  // bearing, world, unit norm
  double sigma_rad = 0;                   // angular error, rad, > 0
};

template <int D>
struct BearingEstimate {
  enum class Outcome { kInitialised, kTooParallel, kOutOfRange };
  Outcome outcome = Outcome::kTooParallel;
  Eigen::Matrix<double, D, 1> mean_m = Eigen::Matrix<double, D, 1>::Zero();  // world, m
  Eigen::Matrix<double, D, D> cov_m2 = Eigen::Matrix<double, D, D>::Zero();  // m^2
  Eigen::Matrix<double, D, 1> intersection_m = Eigen::Matrix<double, D, 1>::Zero();
  double parallax_rad = 0;  // largest angle between two bearings
  int draws = 0;            // points drawn (acceptance = num_samples / draws)
  int restarts = 0;         // times p_max was raised (earlier samples thinned)
  int growths = 0;          // passes repeated with a larger box
};

template <int D>
class BearingInitializer {
 public:
  using Vec = Eigen::Matrix<double, D, 1>;
  explicit BearingInitializer(const BearingInitParams& params);
  const Status& initStatus() const { return init_status_; }

  // Fuses views (>= 2, finite, unit directions, sigma > 0) into out. kInitialised: out's mean
  // and covariance are the samples'; kTooParallel / kOutOfRange: nothing was sampled (wait for
  // another view). An error Status for bad input or when max_draws did not give num_samples.
  Status process(const std::vector<BearingView<D>>& views, std::uint64_t stream,
                 BearingEstimate<D>& out);
  // The samples kept by the last successful process() (num_samples of them, world, m), e.g. to
  // carry them into another frame as seed 003 does.
  const std::vector<Vec>& samples() const { return samples_; }
  // log of the unnormalised density prod_k p_k at x (-infinity outside a view's range).
  double logDensity(const std::vector<BearingView<D>>& views, const Vec& x) const;

 private:
  BearingInitParams params_;
  Status init_status_;
  std::vector<Vec> samples_;
};

extern template class BearingInitializer<2>;
extern template class BearingInitializer<3>;

}  // namespace svslam
