#pragma once
// The temporal matcher tests' scene, with exact ground truth: two textured planes (a tilted
// background wall and a closer fronto-parallel panel) rendered by ray casting from two known
// camera poses; the stereo points of both frames come from the true geometry plus seeded noise
// drawn from their stated covariance.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <random>
#include <vector>

#include "core/camera.hpp"
#include "core/image.hpp"
#include "features/temporal_matcher.hpp"
#include "wave_texture.hpp"

namespace svslam::temporal_scene {

// Continuous band-limited texture on a plane (metres): 24 plane waves.
struct Texture : test_texture::WaveTexture {
  Texture(unsigned seed, double lambda_min_m, double lambda_max_m)
      : WaveTexture(seed, lambda_min_m, lambda_max_m, 24, 55.0) {}
};

// World frame = previous left camera frame. Background: the plane -0.2 x + 0.1 y + z = 4
// (z ~ 3.4 .. 4.6 m in view); panel: z = 2.5 m for x in [-0.9, -0.1], y in [-0.6, 0.5].
struct World {
  PinholeCamera cam{400.0, 400.0, 160.0, 120.0, 320, 240};
  Texture bg{5, 0.08, 0.5}, panel{6, 0.06, 0.3};

  // Nearest surface point along origin + t dir (t > 0), world frame; false when none.
  bool cast(const Eigen::Vector3d& o, const Eigen::Vector3d& dir, Eigen::Vector3d& X,
            int& surface) const {
    double best = HUGE_VAL;
    if (std::abs(dir.z()) > 1e-12) {
      const double t = (2.5 - o.z()) / dir.z();
      const Eigen::Vector3d q = o + t * dir;
      if (t > 0 && q.x() >= -0.9 && q.x() <= -0.1 && q.y() >= -0.6 && q.y() <= 0.5) {
        best = t;
        X = q;
        surface = 1;
      }
    }
    const Eigen::Vector3d n(-0.2, 0.1, 1.0);
    const double den = n.dot(dir);
    if (std::abs(den) > 1e-12) {
      const double t = (4.0 - n.dot(o)) / den;
      if (t > 0 && t < best) {
        best = t;
        X = o + t * dir;
        surface = 0;
      }
    }
    return best < HUGE_VAL;
  }
  // Ray of pixel (u, v) of a camera with pose T_cam_world, in the world frame.
  bool castPixel(const Eigen::Isometry3d& T_cam_world, double u, double v, Eigen::Vector3d& X,
                 int& surface) const {
    const Eigen::Isometry3d T_world_cam = T_cam_world.inverse();
    const Eigen::Vector3d d_cam((u - cam.cx_px) / cam.fx_px, (v - cam.cy_px) / cam.fy_px, 1.0);
    return cast(T_world_cam.translation(), T_world_cam.linear() * d_cam, X, surface);
  }
  double shade(const Eigen::Vector3d& X, int surface) const {
    return surface == 1 ? panel(X.x(), X.y()) : bg(X.x(), X.y());
  }
  ImageU8 render(const Eigen::Isometry3d& T_cam_world) const {
    ImageU8 img(cam.width, cam.height);
    for (int v = 0; v < cam.height; ++v)
      for (int u = 0; u < cam.width; ++u) {
        Eigen::Vector3d X;
        int s = 0;
        const double g = castPixel(T_cam_world, u, v, X, s) ? shade(X, s) : 0.0;
        img(u, v) = static_cast<std::uint8_t>(std::clamp(std::lround(g), 0L, 255L));
      }
    return img;
  }
};

// Stereo-like covariance of a point p_cam (b = 0.3 m, sigma 0.3 px in u, v and d): lateral
// sigma z s / f, along the ray z^2 s / (f b).
inline Eigen::Matrix3d stereoCov(const PinholeCamera& cam, const Eigen::Vector3d& p_cam,
                                 Eigen::Matrix3d& L) {
  const double z = p_cam.z(), s = 0.3, b = 0.3;
  const double sl = z * s / cam.fx_px, sz = z * z * s / (cam.fx_px * b);
  const Eigen::Vector3d r = p_cam.normalized();
  Eigen::Vector3d a = r.cross(Eigen::Vector3d::UnitX()).normalized();
  const Eigen::Vector3d c = r.cross(a);
  Eigen::Matrix3d B;
  B << a, c, r;
  L = B * Eigen::Vector3d(sl, sl, sz).asDiagonal();
  return L * L.transpose();
}

inline TrackPoint makePoint(const PinholeCamera& cam, double u, double v,
                            const Eigen::Vector3d& p_true, std::mt19937& rng) {
  std::normal_distribution<double> n01(0, 1);
  TrackPoint p;
  p.u_px = static_cast<float>(u);
  p.v_px = static_cast<float>(v);
  Eigen::Matrix3d L;
  p.cov = stereoCov(cam, p_true, L);
  p.p_cam = p_true + L * Eigen::Vector3d(n01(rng), n01(rng), n01(rng));
  return p;
}

inline bool patchIn(const PinholeCamera& cam, double u, double v, int h) {
  const long x = std::lround(u), y = std::lround(v);
  return x - h >= 0 && y - h >= 0 && x + h < cam.width && y + h < cam.height;
}

struct Frames {
  World world;
  Eigen::Isometry3d T_cur_prev = Eigen::Isometry3d::Identity();
  ImageU8 prev_img, cur_img;
  std::vector<TrackPoint> prev, cur;
  std::vector<int> truth;  // current index of each previous point, -1 when it has none
  int visible = 0;         // previous points with a counterpart, both patches inside (h = 5)
};

inline const Frames& frames() {
  static const Frames f = [] {
    Frames out;
    const World& w = out.world;
    const PinholeCamera& cam = w.cam;
    // ~3.2 degrees about a skewed axis, 0.3 m of translation.
    out.T_cur_prev.linear() =
        Eigen::AngleAxisd(0.056, Eigen::Vector3d(0.3, 1.0, 0.2).normalized()).toRotationMatrix();
    out.T_cur_prev.translation() = Eigen::Vector3d(0.15, -0.05, 0.25);
    out.prev_img = w.render(Eigen::Isometry3d::Identity());
    out.cur_img = w.render(out.T_cur_prev);
    std::mt19937 rng(2024);
    std::uniform_int_distribution<int> ux(0, cam.width - 1), uy(0, cam.height - 1);
    std::vector<Eigen::Vector2d> used;
    std::vector<TrackPoint> cur_true;  // before shuffling
    std::vector<int> cur_of_prev;
    while (out.prev.size() < 420) {
      const int u = ux(rng), v = uy(rng);
      bool near = false;
      for (const auto& q : used) near = near || (q - Eigen::Vector2d(u, v)).norm() < 5.0;
      if (near) continue;
      used.emplace_back(u, v);
      Eigen::Vector3d X;
      int s = 0;
      if (!w.castPixel(Eigen::Isometry3d::Identity(), u, v, X, s)) continue;
      out.prev.push_back(makePoint(cam, u, v, X, rng));
      // Counterpart: the projection into the current image when not occluded there.
      const Eigen::Vector3d Xc = out.T_cur_prev * X;
      double uc, vc;
      int idx = -1;
      if (cam.project(Xc.x(), Xc.y(), Xc.z(), uc, vc) && uc >= 0 && vc >= 0 &&
          uc <= cam.width - 1 && vc <= cam.height - 1) {
        Eigen::Vector3d Y;
        int s2 = 0;
        if (w.castPixel(out.T_cur_prev, uc, vc, Y, s2) && (Y - X).norm() < 1e-6) {
          idx = static_cast<int>(cur_true.size());
          cur_true.push_back(makePoint(cam, uc, vc, Xc, rng));
          if (patchIn(cam, u, v, 5) && patchIn(cam, uc, vc, 5)) ++out.visible;
        }
      }
      cur_of_prev.push_back(idx);
    }
    // Points detected in the current frame only, away from the counterparts.
    const std::size_t n_true = cur_true.size();
    std::uniform_real_distribution<double> fu(0, cam.width - 1), fv(0, cam.height - 1);
    while (cur_true.size() < n_true + 80) {
      const double u = fu(rng), v = fv(rng);
      bool near = false;
      for (const auto& c : cur_true) near = near || std::hypot(c.u_px - u, c.v_px - v) < 4.0;
      if (near) continue;
      Eigen::Vector3d X;
      int s = 0;
      if (!w.castPixel(out.T_cur_prev, u, v, X, s)) continue;
      cur_true.push_back(makePoint(cam, u, v, out.T_cur_prev * X, rng));
    }
    std::vector<int> perm(cur_true.size());  // perm[old] = new
    std::iota(perm.begin(), perm.end(), 0);
    std::shuffle(perm.begin(), perm.end(), rng);
    out.cur.resize(cur_true.size());
    for (std::size_t i = 0; i < cur_true.size(); ++i)
      out.cur[static_cast<std::size_t>(perm[i])] = cur_true[i];
    for (int c : cur_of_prev) out.truth.push_back(c < 0 ? -1 : perm[static_cast<std::size_t>(c)]);
    return out;
  }();
  return f;
}

}  // namespace svslam::temporal_scene
