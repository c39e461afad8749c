// Rotation by coarse image alignment (motion/rotation_alignment.hpp): a textured image warped by
// a known rotation homography K R K^-1, with a brightness change, is aligned back; starts far
// from the truth are found by the coarse grid; bad inputs are refused.
#include "motion/rotation_alignment.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "motion/visual_motion.hpp"

namespace svslam {
namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;

PinholeCamera camera() {
  PinholeCamera c;
  c.fx_px = c.fy_px = 460.0;
  c.cx_px = 367.0;
  c.cy_px = 248.0;
  return c;
}

// A smooth random texture defined on the unit sphere of directions, so that any rotation of
// the camera sees a consistent scene: the sum of Gaussian blobs placed at random directions.
struct SphereTexture {
  std::vector<Eigen::Vector3d> dirs;
  std::vector<double> amp;
  explicit SphereTexture(unsigned seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> n(0.0, 1.0);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (int i = 0; i < 1500; ++i) {
      Eigen::Vector3d d(n(rng), n(rng), n(rng) + 2.5);
      dirs.push_back(d.normalized());
      amp.push_back(u(rng));
    }
  }
  double at(const Eigen::Vector3d& ray) const {
    const Eigen::Vector3d r = ray.normalized();
    double v = 128.0;
    for (std::size_t i = 0; i < dirs.size(); ++i) {
      const double c = (r - dirs[i]).squaredNorm();
      if (c < 0.01) v += 60.0 * amp[i] * std::exp(-c / (2.0 * 0.012 * 0.012));
    }
    return std::clamp(v, 0.0, 255.0);
  }
};

// The image of camera c rotated by R_cam_ref (a ray d of the reference frame is R d in it).
ImageU8 render(const SphereTexture& tex, const PinholeCamera& c, const Eigen::Matrix3d& R_cam_ref,
               double gain, double bias, int w, int h) {
  ImageU8 img(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const Eigen::Vector3d ray((x - c.cx_px) / c.fx_px, (y - c.cy_px) / c.fy_px, 1.0);
      const double v = gain * tex.at(R_cam_ref.transpose() * ray) + bias;
      img(x, y) = static_cast<std::uint8_t>(std::lround(std::clamp(v, 0.0, 255.0)));
    }
  return img;
}

double angleDeg(const Eigen::Matrix3d& A, const Eigen::Matrix3d& B) {
  return logSO3(A * B.transpose()).norm() / kDeg;
}

TEST(RotationAlignment, RecoversATurnWithABrightnessChange) {
  const int w = 376, h = 240;
  PinholeCamera cam = camera();
  cam.fx_px = cam.fy_px = 230.0;
  cam.cx_px = 183.5;
  cam.cy_px = 123.5;
  const SphereTexture tex(7);
  const Eigen::Matrix3d R_prev = Eigen::Matrix3d::Identity();
  const Eigen::Matrix3d R_cur = expSO3(Eigen::Vector3d(-1.7, -7.7, -4.9) * kDeg);
  const ImageU8 prev = render(tex, cam, R_prev, 1.0, 0.0, w, h);
  const ImageU8 cur = render(tex, cam, R_cur, 1.1, -8.0, w, h);
  RotationAlignmentParams p;
  p.coarsest_level = 3;
  p.finest_level = 1;
  RotationAlignment align(p, w, h);
  ASSERT_TRUE(align.initStatus().isOk()) << align.initStatus().message();
  RotationAlignmentResult out;
  // The constant-velocity start of a turn that changed: 5 degrees off, the in-plane part wrong.
  const std::vector<Eigen::Matrix3d> starts = {expSO3(Eigen::Vector3d(1.6, -3.7, -3.3) * kDeg),
                                               Eigen::Matrix3d::Identity()};
  ASSERT_TRUE(align.process(prev.cview(), cur.cview(), cam, starts, out).isOk());
  const Eigen::Matrix3d R_cur_prev = R_cur * R_prev.transpose();
  EXPECT_LT(angleDeg(out.R_cur_prev, R_cur_prev), 0.1) << "rms " << out.rms_grey;
  EXPECT_LT(out.rms_grey, 3.0);
  EXPECT_GT(out.overlap, 0.6);
}

TEST(RotationAlignment, GridFindsATurnFarFromEveryStart) {
  const SphereTexture tex(11);
  const int w = 752, h = 480;
  const Eigen::Matrix3d R_cur = expSO3(Eigen::Vector3d(3.0, 10.0, 1.0) * kDeg);
  const ImageU8 prev = render(tex, camera(), Eigen::Matrix3d::Identity(), 1.0, 0.0, w, h);
  const ImageU8 cur = render(tex, camera(), R_cur, 1.0, 0.0, w, h);
  RotationAlignmentParams p;
  RotationAlignment align(p, w, h);
  RotationAlignmentResult out;
  ASSERT_TRUE(align.process(prev.cview(), cur.cview(), camera(), {Eigen::Matrix3d::Identity()}, out)
                  .isOk());
  EXPECT_LT(angleDeg(out.R_cur_prev, R_cur), 0.1);
  p.search_deg = 0.0;  // without the grid, the identity start cannot reach a 10-degree turn
  RotationAlignment local(p, w, h);
  RotationAlignmentResult out2;
  const bool found =
      local.process(prev.cview(), cur.cview(), camera(), {Eigen::Matrix3d::Identity()}, out2)
          .isOk();
  if (found) {
    EXPECT_GT(angleDeg(out2.R_cur_prev, R_cur), 1.0);
  }
}

TEST(RotationAlignment, BadInputsAreRefused) {
  RotationAlignmentParams p;
  p.finest_level = 5;
  EXPECT_FALSE(p.validate().isOk());
  p = RotationAlignmentParams{};
  p.huber_grey = std::nan("");
  EXPECT_FALSE(p.validate().isOk());
  p = RotationAlignmentParams{};
  EXPECT_FALSE(RotationAlignment(p, 64, 64).initStatus().isOk());  // 4x4 at level 4
  RotationAlignment align(p, 320, 240);
  ImageU8 a(320, 240), b(160, 120);
  RotationAlignmentResult out;
  EXPECT_FALSE(align.process(a.cview(), b.cview(), camera(), {Eigen::Matrix3d::Identity()}, out)
                   .isOk());
  EXPECT_FALSE(align.process(a.cview(), a.cview(), camera(), {}, out).isOk());
}

}  // namespace
}  // namespace svslam
