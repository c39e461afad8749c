#pragma once
// The rendered scene of the stereo point matcher tests: a rectified pair from a continuous
// procedural texture with a known piecewise planar disparity (a slanted plane and a box).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <set>
#include <utility>
#include <vector>

#include "core/image.hpp"
#include "features/stereo_point_matcher.hpp"
#include "wave_texture.hpp"

namespace svslam::stereo_scene {

// ------------------------------------------------------------------------------------------
// Stereo point matcher
// ------------------------------------------------------------------------------------------

// Continuous band-limited texture (pixels): 32 plane waves, wavelengths 5..40 px.
struct Texture : test_texture::WaveTexture {
  explicit Texture(unsigned seed) : WaveTexture(seed, 5.0, 40.0, 32, 55.0) {}
};

inline std::uint8_t toU8(double v) {
  return static_cast<std::uint8_t>(std::clamp(std::lround(v), 0L, 255L));
}

// Scene in left-image coordinates: a slanted plane d = a + b x + c y and a fronto-parallel box
// (closer: larger disparity) with its own texture. Optionally a rectangle of vertical stripes
// (period 8 px) painted on the plane.
struct Scene {
  int w = 320, h = 240;
  double pa = 20.0, pb = 0.03, pc = 0.02;  // plane disparity
  int bx0 = 180, bx1 = 260, by0 = 60, by1 = 170;
  double box_d = 48.0;
  bool box = true;
  bool stripes = false;
  int sx0 = 30, sx1 = 150, sy0 = 20, sy1 = 100;
  Texture tex{11}, box_tex{29};

  bool inBox(double x, double y) const { return box && x >= bx0 && x < bx1 && y >= by0 && y < by1; }
  double planeD(double x, double y) const { return pa + pb * x + pc * y; }
  double truth(int x, int y) const { return inBox(x, y) ? box_d : planeD(x, y); }
  // Texture of the plane at left-image coordinates (x, y).
  double planeTex(double x, double y) const {
    if (stripes && x >= sx0 && x < sx1 && y >= sy0 && y < sy1)
      return 128.0 + 80.0 * std::sin(2 * M_PI * x / 8.0);
    return tex(x, y);
  }
  // A left point whose plane patch is hidden in the right image behind the box.
  bool occluded(int x, int y) const {
    if (!box || inBox(x, y) || y < by0 || y >= by1) return false;
    const double xr = x - planeD(x, y);
    return xr >= bx0 - box_d && xr < bx1 - box_d;
  }
  ImageU8 left() const {
    ImageU8 img(w, h);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) img(x, y) = toU8(inBox(x, y) ? box_tex(x, y) : planeTex(x, y));
    return img;
  }
  // R(xr, y) = surface texture at the left coordinate xl with xl - d(xl, y) = xr; the box hides
  // the plane where both map.
  ImageU8 right() const {
    ImageU8 img(w, h);
    for (int y = 0; y < h; ++y)
      for (int xr = 0; xr < w; ++xr) {
        const double xb = xr + box_d;
        if (inBox(xb, y)) {
          img(xr, y) = toU8(box_tex(xb, y));
        } else {
          const double xp = (xr + pa + pc * y) / (1.0 - pb);
          img(xr, y) = toU8(planeTex(xp, y));
        }
      }
    return img;
  }
};

inline std::vector<Eigen::Vector2f> randomPixels(int n, int w, int h, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> ux(0, w - 1), uy(0, h - 1);
  std::set<std::pair<int, int>> used;
  std::vector<Eigen::Vector2f> p;
  while (static_cast<int>(p.size()) < n) {
    const int x = ux(rng), y = uy(rng);
    if (!used.insert({x, y}).second) continue;
    p.emplace_back(static_cast<float>(x), static_cast<float>(y));
  }
  return p;
}

inline double percentile(std::vector<double> v, double q) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const std::size_t k =
      std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size())));
  return v[k];
}

inline double errorOf(const Scene& s, const StereoMatch& m) {
  return std::abs(m.d_px - s.truth(static_cast<int>(std::lround(m.u_px)),
                                   static_cast<int>(std::lround(m.v_px))));
}

inline StereoMatchParams defaultParams() {
  StereoMatchParams p;
  p.max_disp_px = 64;
  return p;
}

struct Rendered {
  Scene scene;
  ImageU8 left, right;
};

inline const Rendered& boxScene() {
  static const Rendered r = [] {
    Rendered out;
    out.left = out.scene.left();
    out.right = out.scene.right();
    return out;
  }();
  return r;
}

}  // namespace svslam::stereo_scene
