// Seed 003's experiment (section 5.2-B), in simulation: a robot on a 105 x 68 cm field takes a
// panoramic bearing to four landmarks, moves in a straight line and takes a second one. Each
// landmark is initialised in the robot frame R_F (O1 at the origin, O2 along x) by the rejection
// sampling of BearingInitializer<2>; the samples are carried into the landmark frame L_F that
// L1 and L2 (the goal posts, 30 cm apart) define, sample by sample (seed 003 section 4: the
// uncertainty of L1 and L2 passes to the others), and the Gaussians of successive iterations
// are fused in information form (a move where a landmark waits for a better view, parallax
// under 8 sigma, adds nothing). R_min 3 cm, R_max 120 cm, bearing error +-3 degrees read as a 3
// sigma bound (sigma 1 degree: the cone holds 99.7 %; at sigma 1.5 degrees the final errors
// are about 1.7x larger). Landmark positions and move lengths (20-40 cm) are not in the seed;
// they are ours. The seed: the error on L3 falls from about 9 cm at the first iteration to under
// 1 cm after 40; on L4 from 14 to 2.77 cm. Figure 17: four trajectories repeated ten times;
// the fourth, along a line close to L3, is by far the worst (2.12, 1.17, 1.51, 13.99 cm).
// Known limit, measured here: the estimates carried through L_F are biased toward L1 (the
// noisy L1-L2 baseline is too long on average, so the similarity shrinks), and the information
// fusion weights the shrunk ones more: 2-4 sigma off after ten iterations of one trajectory.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <random>
#include <vector>

#include "slam/bearing_initializer.hpp"

namespace svslam {
namespace {

using Eigen::Matrix2d;
using Eigen::Vector2d;
using cplx = std::complex<double>;

constexpr double kDeg = M_PI / 180.0;
constexpr double kSigma = 1.0 * kDeg;  // +-3 degrees as 3 sigma

const Vector2d kL1(0, 19), kL2(0, 49);  // goal posts, 30 cm apart (field coordinates, cm)
const Vector2d kL3(35, 30), kL4(75, 55);

BearingInitParams seedParams(double min_parallax_sigmas) {
  BearingInitParams p;
  p.r_min_m = 3;  // the test works in cm
  p.r_max_m = 120;
  p.num_samples = 2000;
  p.min_parallax_sigmas = min_parallax_sigmas;
  p.max_draws = 20000000;  // the raw estimate of nearly parallel views (no gate) is costly
  return p;
}

// One straight move O1 -> O2 (field, cm). Returns false when a landmark could not be
// initialised (too parallel or out of range); else the Gaussian of each target landmark in the
// field frame, obtained through L_F.
struct Fused {
  Matrix2d info = Matrix2d::Zero();
  Vector2d info_mean = Vector2d::Zero();
  int used = 0;
  Vector2d mean() const { return info.ldlt().solve(info_mean); }
  void add(const Vector2d& m, const Matrix2d& C) {
    const Matrix2d I = C.inverse();
    info += I;
    info_mean += I * m;
    ++used;
  }
};

bool observeMove(BearingInitializer<2>& init, const Vector2d& o1, const Vector2d& o2,
                 const std::vector<Vector2d>& targets, std::mt19937_64& rng,
                 std::uint64_t stream, std::vector<Vector2d>& means,
                 std::vector<Matrix2d>& covs) {
  std::normal_distribution<double> noise(0, kSigma);
  // Robot frame R_F: O1 at the origin, x along the move (the robot's heading is not known in
  // the field: only its own bearings are).
  const Vector2d ax = (o2 - o1).normalized();
  const auto toRobot = [&](const Vector2d& p) {
    const Vector2d d = p - o1;
    return Vector2d(d.dot(ax), -d.x() * ax.y() + d.y() * ax.x());
  };
  const Vector2d r1(0, 0), r2 = toRobot(o2);
  std::vector<Vector2d> all = {kL1, kL2};
  all.insert(all.end(), targets.begin(), targets.end());
  std::vector<std::vector<Vector2d>> samples;
  for (std::size_t j = 0; j < all.size(); ++j) {
    const Vector2d l = toRobot(all[j]);
    std::vector<BearingView<2>> views;
    for (const Vector2d& o : {r1, r2}) {
      const Vector2d v = l - o;
      const double b = std::atan2(v.y(), v.x()) + noise(rng);
      views.push_back({o, Vector2d(std::cos(b), std::sin(b)), kSigma});
    }
    BearingEstimate<2> est;
    const Status st = init.process(views, stream * 16 + j, est);
    if (!st) return false;
    if (est.outcome != BearingEstimate<2>::Outcome::kInitialised) return false;
    samples.push_back(init.samples());
  }
  // L_F, sample by sample: the similarity taking (s1, s2) to (L1, L2); expressed in field
  // coordinates (L_F scaled by |L1 L2| = 30 cm) so that errors read in cm.
  const cplx L1(kL1.x(), kL1.y()), L2(kL2.x(), kL2.y());
  means.clear();
  covs.clear();
  const std::size_t n = samples[0].size();
  for (std::size_t t = 2; t < all.size(); ++t) {
    std::vector<Vector2d> moved(n);
    Vector2d mean = Vector2d::Zero();
    for (std::size_t k = 0; k < n; ++k) {
      const cplx a1(samples[0][k].x(), samples[0][k].y()), a2(samples[1][k].x(), samples[1][k].y());
      const cplx x(samples[t][k].x(), samples[t][k].y());
      const cplx y = L1 + (x - a1) * (L2 - L1) / (a2 - a1);
      moved[k] = Vector2d(y.real(), y.imag());
      mean += moved[k];
    }
    mean /= static_cast<double>(n);
    Matrix2d C = Matrix2d::Zero();
    for (const Vector2d& m : moved) C += (m - mean) * (m - mean).transpose();
    C /= static_cast<double>(n - 1);
    means.push_back(mean);
    covs.push_back(C);
  }
  return true;
}

// 40 random straight moves (start uniform on the field 5 cm from its edges, heading uniform,
// length 15-30 cm, staying on the field). Returns the error of L3 and L4 after each iteration.
void randomMoves(std::uint64_t seed, std::vector<double>& err3, std::vector<double>& err4,
                 int& skipped) {
  BearingInitializer<2> init(seedParams(8));
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> ux(5, 100), uy(5, 63), uh(-M_PI, M_PI), ul(20, 40);
  Fused f3, f4;
  skipped = 0;
  err3.clear();
  err4.clear();
  for (int it = 0; static_cast<int>(err3.size()) < 40; ++it) {
    const Vector2d o1(ux(rng), uy(rng));
    const double h = uh(rng);
    const Vector2d o2 = o1 + ul(rng) * Vector2d(std::cos(h), std::sin(h));
    if (o2.x() < 0 || o2.x() > 105 || o2.y() < 0 || o2.y() > 68) continue;
    std::vector<Vector2d> means;
    std::vector<Matrix2d> covs;
    if (!observeMove(init, o1, o2, {kL3, kL4}, rng, static_cast<std::uint64_t>(it), means,
                     covs)) {
      ++skipped;  // a landmark waited: the iteration brings nothing
      continue;
    }
    f3.add(means[0], covs[0]);
    f4.add(means[1], covs[1]);
    err3.push_back((f3.mean() - kL3).norm());
    err4.push_back((f4.mean() - kL4).norm());
  }
}

TEST(BearingSeed003, FortyRandomMovesShrinkTheError) {
  // Ten independent experiments (the seed ran one): first-iteration and final errors.
  std::vector<double> first3, last3, first4, last4;
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    std::vector<double> e3, e4;
    int skipped = 0;
    randomMoves(seed, e3, e4, skipped);
    ASSERT_EQ(e3.size(), 40u);
    std::printf("seed003 run %2d: L3 %.2f -> %.2f cm, L4 %.2f -> %.2f cm (%d moves waited)\n",
                static_cast<int>(seed), e3.front(), e3.back(), e4.front(), e4.back(), skipped);
    first3.push_back(e3.front());
    last3.push_back(e3.back());
    first4.push_back(e4.front());
    last4.push_back(e4.back());
  }
  const auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
  };
  std::printf("seed003 medians over 10 runs: L3 %.2f -> %.2f cm, L4 %.2f -> %.2f cm\n",
              median(first3), median(last3), median(first4), median(last4));
  // The seed: L3 about 9 cm -> under 1 cm; L4 14 -> 2.77 cm.
  EXPECT_LT(median(last3), 1.0);
  EXPECT_GT(median(first3), 3 * median(last3));
  EXPECT_LT(*std::max_element(last3.begin(), last3.end()), 2.0);
  EXPECT_LT(median(last4), 3.0);
  EXPECT_GT(median(last4), median(last3));  // farther from L1 and L2: larger error
}

// Figure 17: four trajectories, ten iterations each (the same move, fresh noise). The fourth
// runs along a line passing 0.5 cm from L3 (toward it): the two cones on L3 are nearly the same.
TEST(BearingSeed003, MovingTowardTheLandmarkIsWorst) {
  const std::vector<std::pair<Vector2d, Vector2d>> moves = {
      {{20, 5}, {20, 25}}, {{55, 40}, {55, 60}}, {{15, 62}, {40, 62}}, {{35.2, 60}, {35.4, 45}}};
  std::vector<double> err(moves.size());
  for (std::size_t t = 0; t < moves.size(); ++t) {
    BearingInitializer<2> init(seedParams(0));  // no parallax gate: see the raw estimate
    std::mt19937_64 rng(100 + t);
    Fused f;
    for (int it = 0; it < 10; ++it) {
      std::vector<Vector2d> means;
      std::vector<Matrix2d> covs;
      if (observeMove(init, moves[t].first, moves[t].second, {kL3}, rng,
                      static_cast<std::uint64_t>(it), means, covs))
        f.add(means[0], covs[0]);
    }
    err[t] = f.used > 0 ? (f.mean() - kL3).norm() : INFINITY;
    std::printf("seed003 figure 17, trajectory %d: L3 error %.2f cm after 10 iterations (%d of "
                "them initialised it)\n",
                static_cast<int>(t + 1), err[t], f.used);
  }
  // The seed: 2.12, 1.17, 1.51, 13.99 cm.
  for (int t = 0; t < 3; ++t) EXPECT_LT(err[t], 4.0) << t;
  EXPECT_GT(err[3], 2.5 * std::max({err[0], err[1], err[2]}));
  // With the experiment's gate (8 sigma) the fourth trajectory's L3 waits for a better view.
  BearingInitializer<2> gated(seedParams(8));
  const Vector2d o1 = moves[3].first, o2 = moves[3].second;
  std::vector<BearingView<2>> views;
  for (const Vector2d& o : {o1, o2}) {
    const Vector2d v = (kL3 - o).normalized();
    views.push_back({o, v, kSigma});
  }
  BearingEstimate<2> est;
  ASSERT_TRUE(gated.process(views, 0, est));
  EXPECT_EQ(est.outcome, BearingEstimate<2>::Outcome::kTooParallel);
}

}  // namespace
}  // namespace svslam
