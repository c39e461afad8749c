// The synthetic stereo flight against independent references: terrain points projected with the
// pinhole model land on matching texture in both views, dense stereo on the rendered pair
// recovers f b / z, ray-cast depths lie on the surface and are the FIRST hit (slow fixed-step
// reference), closed loop geometry, determinism, option errors naming the key, the rover variant.
#include "drivers/synthetic/synthetic_flight.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <vector>

#include "drivers/source/stereo_source.hpp"
#include "stereo/dense_stereo.hpp"

namespace svslam::drivers {
namespace {

SyntheticFlight makeFlight(const std::string& options) {
  auto p = parseSyntheticOptions(options);
  EXPECT_TRUE(p.isOk()) << p.status().message();
  return SyntheticFlight(p.isOk() ? *p : SyntheticFlightParams{});
}

double median(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

double bilinear(const ImageU8& im, double u, double v) {
  const int x = static_cast<int>(std::floor(u)), y = static_cast<int>(std::floor(v));
  const double a = u - x, b = v - y;
  return (1 - a) * (1 - b) * im(x, y) + a * (1 - b) * im(x + 1, y) + (1 - a) * b * im(x, y + 1) +
         a * b * im(x + 1, y + 1);
}

// ZNCC of the 11 x 11 patches centred on (ul, vl) in `l` and (ur, vr) in `r` (bilinear samples).
double zncc(const ImageU8& l, double ul, double vl, const ImageU8& r, double ur, double vr) {
  double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0;
  const int n = 121;
  for (int dy = -5; dy <= 5; ++dy)
    for (int dx = -5; dx <= 5; ++dx) {
      const double a = bilinear(l, ul + dx, vl + dy), b = bilinear(r, ur + dx, vr + dy);
      sa += a;
      sb += b;
      saa += a * a;
      sbb += b * b;
      sab += a * b;
    }
  const double va = saa - sa * sa / n, vb = sbb - sb * sb / n;
  return (sab - sa * sb / n) / std::sqrt(std::max(va * vb, 1e-12));
}

// Projects world point P with T_W_C and the calibration; false when behind or outside (margin).
bool projectPoint(const Eigen::Isometry3d& T_W_C, const StereoCalibration& c,
                  const Eigen::Vector3d& P, double margin, double& u, double& v) {
  const Eigen::Vector3d p = T_W_C.inverse() * P;
  if (p.z() <= 0) return false;
  u = c.f_px * p.x() / p.z() + c.cx_px;
  v = c.f_px * p.y() / p.z() + c.cy_px;
  return u >= margin && v >= margin && u < c.width - 1 - margin && v < c.height - 1 - margin;
}

TEST(SyntheticFlight, ProjectedTerrainPointsMatchInBothViews) {
  const SyntheticFlight f = makeFlight("width=640,height=480,frames=40");
  const auto& c = f.calibration();
  for (int frame : {0, 13, 27}) {
    ImageU8 l, r;
    ASSERT_TRUE(f.render(frame, l, r).isOk());
    const Eigen::Isometry3d T_l = f.pose(frame);
    // Independent right pose: +baseline along the left camera's x axis.
    Eigen::Isometry3d T_r = T_l;
    T_r.translation() += T_l.linear().col(0) * c.baseline_m;
    std::vector<double> at_truth, shifted;
    for (double dx = -12; dx <= 12; dx += 2.0)
      for (double dy = -9; dy <= 9; dy += 2.0) {
        const double x = T_l.translation().x() + dx + 0.37, y = T_l.translation().y() + dy + 0.21;
        const Eigen::Vector3d P(x, y, f.heightAt(x, y));
        double ul, vl, ur, vr;
        if (!projectPoint(T_l, c, P, 12, ul, vl) || !projectPoint(T_r, c, P, 12, ur, vr)) continue;
        EXPECT_NEAR(vl, vr, 1e-9);  // rectified
        at_truth.push_back(zncc(l, ul, vl, r, ur, vr));
        if (ur + 3 < c.width - 13) shifted.push_back(zncc(l, ul, vl, r, ur + 3, vr));
      }
    ASSERT_GT(at_truth.size(), 60u);
    std::sort(at_truth.begin(), at_truth.end());
    const double p10 = at_truth[at_truth.size() / 10];
    std::printf(
        "frame %d: %zu points, ZNCC at truth min %.3f p10 %.3f median %.3f; at +3 px "
        "median %.3f\n",
        frame, at_truth.size(), at_truth.front(), p10, median(at_truth), median(shifted));
    EXPECT_GT(p10, 0.9);
    EXPECT_GT(median(at_truth), 0.95);
    EXPECT_LT(median(shifted), 0.6);
  }
}

TEST(SyntheticFlight, DenseStereoRecoversTheTrueDisparity) {
  const SyntheticFlight f = makeFlight("width=640,height=480,frames=40,seed=5");
  ImageU8 l, r;
  ImageF32 depth, d_true;
  ASSERT_TRUE(f.render(9, l, r, &depth).isOk());
  ASSERT_TRUE(f.trueDisparity(9, d_true).isOk());
  DenseStereoParams p;
  p.min_disp = 16;
  p.max_disp = 112;
  DenseStereo stereo(p, l.width(), l.height());
  ASSERT_TRUE(stereo.initStatus().isOk()) << stereo.initStatus().message();
  DisparityResult out;
  ASSERT_TRUE(stereo.process(l.cview(), r.cview(), out).isOk());
  const auto& c = f.calibration();
  std::vector<double> err;
  int bad = 0, truth_in_range = 0;
  for (int y = 0; y < l.height(); ++y)
    for (int x = p.max_disp; x < l.width(); ++x) {
      ASSERT_TRUE(std::isfinite(depth(x, y)));
      const double dt = c.f_px * c.baseline_m / depth(x, y);
      ASSERT_NEAR(d_true(x, y), dt, 1e-3);
      truth_in_range += dt > p.min_disp + 1 && dt < p.max_disp - 1;
      const float d = out.disparity_px(x, y);
      if (!std::isfinite(d)) continue;
      err.push_back(std::fabs(d - dt));
      bad += err.back() > 1.0;
    }
  const double valid = static_cast<double>(err.size()) / ((l.width() - p.max_disp) * l.height());
  std::printf("dense stereo: valid %.3f, median |d - d_true| %.3f px, > 1 px %.4f\n", valid,
              median(err), static_cast<double>(bad) / err.size());
  EXPECT_EQ(truth_in_range, (l.width() - p.max_disp) * l.height());
  EXPECT_GT(valid, 0.8);
  EXPECT_LT(median(err), 0.25);
  EXPECT_LT(static_cast<double>(bad) / err.size(), 0.03);
}

// Slow reference: first sign change of the ray height above ground with 5 mm steps (in depth z),
// then bisection. Independent of the renderer's Newton / Lipschitz marching.
double referenceDepth(const SyntheticFlight& f, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                      double range_m) {
  auto above = [&](double t) {
    const Eigen::Vector3d p = o + t * d;
    return p.z() - f.heightAt(p.x(), p.y());
  };
  const double step = 0.005;
  for (double t = step; t * d.norm() < range_m; t += step) {
    if (above(t) > 0) continue;
    double lo = t - step, hi = t;
    for (int i = 0; i < 60; ++i) (above(0.5 * (lo + hi)) > 0 ? lo : hi) = 0.5 * (lo + hi);
    // Within 1 mm of the range limit either answer is right; call it sky.
    return 0.5 * (lo + hi) * d.norm() < range_m - 1e-3 ? 0.5 * (lo + hi) : INFINITY;
  }
  return INFINITY;
}

void checkDepthAgainstReference(const std::string& options, int frame, double range_m) {
  const SyntheticFlight f = makeFlight(options);
  const auto& c = f.calibration();
  ImageF32 depth;
  ASSERT_TRUE(f.renderDepth(frame, depth).isOk());
  const Eigen::Isometry3d T = f.pose(frame);
  int hits = 0, sky = 0;
  for (int y = 1; y < c.height; y += 9)
    for (int x = 3; x < c.width; x += 11) {
      const Eigen::Vector3d d =
          T.linear() * Eigen::Vector3d((x - c.cx_px) / c.f_px, (y - c.cy_px) / c.f_px, 1.0);
      const double z_ref = referenceDepth(f, T.translation(), d, range_m);
      const double z = depth(x, y);
      ASSERT_FALSE(std::isnan(z));
      if (!std::isfinite(z_ref)) {
        EXPECT_FALSE(std::isfinite(z)) << x << "," << y;
        ++sky;
        continue;
      }
      ASSERT_TRUE(std::isfinite(z)) << x << "," << y << " ref " << z_ref;
      // The hit lies on the surface and is the first one; disparity error << 0.01 px.
      EXPECT_NEAR(z, z_ref, 1e-4 * z_ref) << x << "," << y;
      const Eigen::Vector3d P = T.translation() + z * d;
      EXPECT_NEAR(P.z(), f.heightAt(P.x(), P.y()), 1e-5 * z);
      EXPECT_LT(std::fabs(c.f_px * c.baseline_m * (1 / z - 1 / z_ref)), 0.01);
      ++hits;
    }
  std::printf("%s: %d hits, %d sky rays checked\n", options.c_str(), hits, sky);
  EXPECT_GT(hits, 100);
}

TEST(SyntheticFlight, FlatGroundDepthMatchesThePlaneIntersection) {
  for (const char* opts :
       {"relief_m=0,width=160,height=120", "variant=rover,relief_m=0,width=160,height=120"}) {
    const SyntheticFlight f = makeFlight(opts);
    const auto& c = f.calibration();
    ImageF32 depth;
    ASSERT_TRUE(f.renderDepth(3, depth).isOk());
    const Eigen::Isometry3d T = f.pose(3);
    int hits = 0;
    for (int y = 0; y < c.height; ++y)
      for (int x = 0; x < c.width; ++x) {
        // Plane z = 0: o_z + z d_z = 0 with d = R ((u - cx)/f, (v - cy)/f, 1).
        const Eigen::Vector3d d =
            T.linear() * Eigen::Vector3d((x - c.cx_px) / c.f_px, (y - c.cy_px) / c.f_px, 1.0);
        const double z = -T.translation().z() / d.z();
        if (d.z() < 0 && z * d.norm() < f.params().max_range_m * 0.999) {
          ASSERT_NEAR(depth(x, y), z, 2e-6 * z) << opts << " " << x << "," << y;
          ++hits;
        } else if (d.z() >= 0 || z * d.norm() > f.params().max_range_m * 1.001) {
          ASSERT_FALSE(std::isfinite(depth(x, y))) << opts << " " << x << "," << y;
        }
      }
    EXPECT_GT(hits, c.width * c.height / 3) << opts;
  }
}

TEST(SyntheticFlight, RayCastDepthIsTheFirstSurfaceHit) {
  checkDepthAgainstReference("width=320,height=240,frames=20,seed=2", 6, 60.0);
  // Rover: grazing rays, marching path; a short range keeps the reference fast.
  checkDepthAgainstReference(
      "variant=rover,width=320,height=240,frames=20,seed=2,max_range_m=60,relief_m=1.5", 4, 60.0);
}

// Runs the tasks in reverse order: rendering must not depend on the task order.
class ReverseExecutor final : public Executor {
 public:
  void parallelFor(int n, TaskRef fn) override {
    for (int i = n - 1; i >= 0; --i) fn(i);
  }
  int concurrency() const override { return 4; }
};

bool sameBytes(const ImageU8& a, const ImageU8& b) {
  if (a.width() != b.width() || a.height() != b.height()) return false;
  for (int y = 0; y < a.height(); ++y)
    for (int x = 0; x < a.width(); ++x)
      if (a(x, y) != b(x, y)) return false;
  return true;
}

TEST(SyntheticFlight, DeterministicPerSeed) {
  const SyntheticFlight a = makeFlight("width=200,height=150,seed=7");
  const SyntheticFlight b = makeFlight("width=200,height=150,seed=7");
  const SyntheticFlight c = makeFlight("width=200,height=150,seed=8");
  ImageU8 l1, r1, l2, r2, l3, r3;
  ASSERT_TRUE(a.render(4, l1, r1).isOk());
  ReverseExecutor rev;
  ASSERT_TRUE(b.render(4, l2, r2, nullptr, rev).isOk());
  ASSERT_TRUE(c.render(4, l3, r3).isOk());
  EXPECT_TRUE(sameBytes(l1, l2));
  EXPECT_TRUE(sameBytes(r1, r2));
  int differ = 0;
  for (int y = 0; y < l1.height(); ++y)
    for (int x = 0; x < l1.width(); ++x) differ += std::abs(l1(x, y) - l3(x, y)) > 8;
  EXPECT_GT(differ, l1.width() * l1.height() / 2);
  EXPECT_FALSE(sameBytes(l1, r1));
  EXPECT_NE(a.heightAt(3.0, 4.0), c.heightAt(3.0, 4.0));
  // 2 x 2 supersampling renders the same scene (the finer sub-pixel detail averages out).
  const SyntheticFlight ss = makeFlight("width=200,height=150,seed=7,supersample=2");
  ImageU8 l4, r4;
  ASSERT_TRUE(ss.render(4, l4, r4).isOk());
  // Correlation of the 4 x 4 block means (the scene above the pixel scale).
  std::vector<double> m1, m4;
  for (int by = 0; by + 4 <= l1.height(); by += 4)
    for (int bx = 0; bx + 4 <= l1.width(); bx += 4) {
      double a1 = 0, a4 = 0;
      for (int y = by; y < by + 4; ++y)
        for (int x = bx; x < bx + 4; ++x) a1 += l1(x, y), a4 += l4(x, y);
      m1.push_back(a1);
      m4.push_back(a4);
    }
  double s1 = 0, s4 = 0, s11 = 0, s44 = 0, s14 = 0;
  const double n = static_cast<double>(m1.size());
  for (std::size_t i = 0; i < m1.size(); ++i) {
    s1 += m1[i], s4 += m4[i], s11 += m1[i] * m1[i], s44 += m4[i] * m4[i], s14 += m1[i] * m4[i];
  }
  const double z = (s14 - s1 * s4 / n) / std::sqrt((s11 - s1 * s1 / n) * (s44 - s4 * s4 / n));
  std::printf("supersample 2 vs 1: correlation of 4x4 block means %.3f\n", z);
  EXPECT_GT(z, 0.9);
  EXPECT_FALSE(sameBytes(l1, l4));
}

TEST(SyntheticFlight, BlimpFliesAClosedLoopLookingDown) {
  const SyntheticFlight f = makeFlight("");
  const auto& p = f.params();
  ASSERT_EQ(f.size(), 100);
  double horizontal = 0.0, full = 0.0;
  for (int i = 0; i < f.size(); ++i) {
    const Eigen::Isometry3d T = f.pose(i);
    const Eigen::Vector3d a = T.translation(), b = f.pose(i + 1).translation();
    horizontal += (b - a).head<2>().norm();
    full += (b - a).norm();
    EXPECT_GE(a.z(), p.altitude_min_m - 1e-9);
    EXPECT_LE(a.z(), p.altitude_max_m + 1e-9);
    EXPECT_GT(a.z() - f.heightAt(a.x(), a.y()), 15.0);
    // Optical axis within wobble of the nadir.
    EXPECT_LT(T.linear().col(2).z(), -std::cos(2.5 * p.wobble_deg * M_PI / 180));
    EXPECT_NEAR((T.linear().transpose() * T.linear() - Eigen::Matrix3d::Identity()).norm(), 0,
                1e-12);
  }
  EXPECT_NEAR(horizontal, p.loop_length_m, 0.01 * p.loop_length_m);
  EXPECT_NEAR(full, p.loop_length_m, 0.05 * p.loop_length_m);
  const double step = horizontal / f.size();
  const Eigen::Vector3d first = f.pose(0).translation(), last = f.pose(99).translation();
  EXPECT_LT((last - first).norm(), 1.5 * step);
  EXPECT_GT((f.pose(50).translation() - first).norm(), 15.0);  // it does travel
  EXPECT_EQ(f.timeNs(7), 700 * kNsPerMs);
}

TEST(SyntheticFlight, OptionErrorsNameTheKey) {
  auto expectError = [](const std::string& opts, const std::string& key) {
    auto r = openStereoSource("synthetic:" + opts);
    ASSERT_FALSE(r.isOk()) << opts;
    EXPECT_EQ(r.status().code(), StatusCode::kInvalidArgument) << opts;
    EXPECT_NE(r.status().message().find(key), std::string::npos) << r.status().message();
  };
  expectError("bogus=1", "bogus");
  expectError("frames=abc", "frames");
  expectError("frames=0", "frames");
  expectError("width=10", "width");
  expectError("variant=plane", "variant");
  expectError("seed=-3", "seed");
  expectError("baseline_m=nan", "baseline_m");
  expectError("altitude_min_m=50", "altitude_min_m");
  expectError("hfov_deg=", "hfov_deg");
  expectError("noequals", "noequals");
  // A key given twice is an error naming it (not first or last wins).
  expectError("frames=3,width=64,frames=5", "'frames' is given twice");
  expectError("variant=blimp,variant=rover", "'variant' is given twice");
  auto ok = openStereoSource("synthetic:frames=3,width=64,height=48,seed=18446744073709551615");
  ASSERT_TRUE(ok.isOk()) << ok.status().message();
  EXPECT_EQ((*ok)->size(), 3);
  EXPECT_TRUE(openStereoSource("synthetic").isOk());
}

TEST(SyntheticFlight, RoverSeesSkyAndGround) {
  auto src = openStereoSource("synthetic:variant=rover,frames=5,width=320,height=240,seed=3");
  ASSERT_TRUE(src.isOk()) << src.status().message();
  const SyntheticFlight* f = asSyntheticFlight(**src);
  ASSERT_NE(f, nullptr);
  EXPECT_EQ(f->params().variant, FlightVariant::kRover);
  const auto& c = (*src)->calibration();
  EXPECT_NEAR(c.baseline_m, 0.5, 1e-12);
  EXPECT_NEAR(c.f_px, 160.0 / std::tan(M_PI / 6), 1e-9);
  Eigen::Isometry3d T0;
  ASSERT_TRUE((*src)->groundTruth(0, T0));
  EXPECT_LT((T0.matrix() - Eigen::Matrix4d::Identity()).norm(), 1e-12);
  Eigen::Isometry3d T3;
  ASSERT_TRUE((*src)->groundTruth(3, T3));
  EXPECT_LT((T3.matrix() - (f->pose(0).inverse() * f->pose(3)).matrix()).norm(), 1e-12);
  EXPECT_GT(T3.translation().norm(), 0.1);
  EXPECT_FALSE((*src)->groundTruth(5, T3));
  StereoFrame fr;
  for (int i = 0; i < 5; ++i) {
    auto more = (*src)->next(fr);
    ASSERT_TRUE(more.isOk() && *more);
    EXPECT_EQ(fr.index, i);
    EXPECT_EQ(fr.t_ns, i * 100 * kNsPerMs);
  }
  auto end = (*src)->next(fr);
  ASSERT_TRUE(end.isOk());
  EXPECT_FALSE(end.value());
  // Camera height above the ground and forward view.
  const Eigen::Isometry3d T = f->pose(4);
  EXPECT_NEAR(T.translation().z() - f->heightAt(T.translation().x(), T.translation().y()), 1.2,
              1e-12);
  EXPECT_LT(std::fabs(T.linear().col(2).z()), 0.3);
  ImageF32 depth;
  ASSERT_TRUE(f->renderDepth(4, depth).isOk());
  int sky_top = 0, ground_bottom = 0;
  for (int x = 0; x < c.width; ++x) {
    sky_top += !std::isfinite(depth(x, 0)) && !std::isnan(depth(x, 0));
    ground_bottom += std::isfinite(depth(x, c.height - 1)) && depth(x, c.height - 1) > 0.5 &&
                     depth(x, c.height - 1) < 6.0;
  }
  EXPECT_EQ(sky_top, c.width);
  EXPECT_EQ(ground_bottom, c.width);
  // Sky is smooth and bright; ground is textured.
  double sky_mean = 0, ground_var = 0, ground_mean = 0;
  for (int x = 0; x < c.width; ++x) {
    sky_mean += fr.left(x, 2);
    ground_mean += fr.left(x, c.height - 3);
  }
  sky_mean /= c.width;
  ground_mean /= c.width;
  for (int x = 0; x < c.width; ++x)
    ground_var += std::pow(fr.left(x, c.height - 3) - ground_mean, 2);
  EXPECT_GT(sky_mean, 140.0);
  EXPECT_GT(std::sqrt(ground_var / c.width), 10.0);
}

TEST(SyntheticFlight, OtherSourcesAreNotSyntheticFlights) {
  class Dummy final : public StereoSource {
   public:
    const StereoCalibration& calibration() const override { return c_; }
    int size() const override { return 0; }
    Result<bool> next(StereoFrame&) override { return false; }
    StereoCalibration c_;
  };
  EXPECT_EQ(asSyntheticFlight(Dummy()), nullptr);
}

TEST(SyntheticFlight, FullSizePairRenderTime) {
  for (const char* opts : {"", "variant=rover"}) {
    const SyntheticFlight f = makeFlight(opts);
    ImageU8 l, r;
    const auto t0 = std::chrono::steady_clock::now();
    const std::clock_t c0 = std::clock();
    ASSERT_TRUE(f.render(1, l, r).isOk());
    const double cpu_ms = 1e3 * static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC;
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    std::printf("%s 1024x768 pair rendered in %.0f ms wall, %.0f ms CPU (one core)\n",
                toString(f.params().variant), ms, cpu_ms);
    RecordProperty(std::string(toString(f.params().variant)) + "_pair_ms", static_cast<int>(ms));
  }
}

}  // namespace
}  // namespace svslam::drivers
