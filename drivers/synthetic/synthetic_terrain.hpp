#pragma once
// The procedural world of the synthetic flight (synthetic_flight.hpp): a seeded smooth heightfield
// and a band-limited albedo texture, both functions of world (x, y) in metres. Header-only so the
// ray caster inlines the inner loops.
//
// Value noise: lattice values v(i, j) in [-1, 1] from an integer hash of (i, j, key), blended with
// the quintic fade s(u) = 6u^5 - 15u^4 + 10u^3 (C2):
//   n(x, y) = a + (b - a) s(u) + (c - a) s(w) + (a - b - c + d) s(u) s(w),
// u, w the fractional lattice coordinates, a..d the corner values. |dn/du| <= 2 max s' = 3.75, so
// |grad n| <= 3.75 sqrt(2) / cell. The hash is not periodic: no pattern repeats anywhere.
// Every octave is rotated by its own angle and shifted by its own offset, so lattice axes of
// different octaves never line up.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace svslam::drivers::synth {

// Lattice hash: a linear mix of the coordinates and the layer key, then the lowbias32
// finaliser (its two multiply-xorshift rounds decorrelate neighbouring lattice points).
inline std::uint32_t finalizeHash(std::uint32_t h) {
  h ^= h >> 16;
  h *= 0x7feb352du;
  h ^= h >> 15;
  h *= 0x846ca68bu;
  h ^= h >> 16;
  return h;
}
inline constexpr std::uint32_t kHashStepI = 0x9E3779B1u, kHashStepJ = 0x85EBCA77u;
inline std::uint32_t hashLattice(std::int32_t i, std::int32_t j, std::uint32_t key) {
  return finalizeHash(key + static_cast<std::uint32_t>(i) * kHashStepI +
                      static_cast<std::uint32_t>(j) * kHashStepJ);
}

// floor() as an int without a libm call (the build has no SSE4.1 round instruction);
// precondition |v| < 2^31.
inline std::int32_t floorToInt(double v) {
  const auto i = static_cast<std::int32_t>(v);  // truncates towards zero
  return i - (v < static_cast<double>(i) ? 1 : 0);
}

// Uniform in [-1, 1] from the top 24 bits of a hash.
inline double hashToSigned(std::uint32_t h) {
  return static_cast<double>(h >> 8) * (2.0 / 16777216.0) - 1.0;
}

// splitmix64: seeds for layers and per-pixel noise.
inline std::uint64_t mix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

// Max of |grad n| * cell for the value noise above: 2 * 15/8 * sqrt(2).
inline constexpr double kValueNoiseSlopeBound = 5.3033008588991064;
// Max of |d2n/de2| * cell^2 along any unit direction e: |n_uu|, |n_ww| <= 2 max|s''| = 20/sqrt(3),
// |n_uw| <= 4 max(s')^2 = 14.0625, and e_u^2 + e_w^2 = 1, 2 |e_u e_w| <= 1.
inline constexpr double kValueNoiseCurvatureBound = 11.547005383792516 + 14.0625;

// One rotated, shifted lattice of a given cell size (metres).
struct NoiseLayer {
  double inv_cell = 1.0;  // 1 / cell size, 1/m
  double cos_a = 1.0, sin_a = 0.0;
  double off_x = 0.0, off_y = 0.0;  // lattice units
  std::uint32_t key = 0;

  static NoiseLayer make(double cell_m, std::uint64_t seed, std::uint64_t salt) {
    NoiseLayer l;
    const std::uint64_t h = mix64(seed ^ mix64(salt));
    const double angle = static_cast<double>(h >> 40) * (6.283185307179586 / 16777216.0);
    l.inv_cell = 1.0 / cell_m;
    l.cos_a = std::cos(angle);
    l.sin_a = std::sin(angle);
    l.off_x = static_cast<double>((h >> 8) & 0xFFFF) * (1.0 / 64.0);
    l.off_y = static_cast<double>(h & 0xFF) * 3.7;
    l.key = static_cast<std::uint32_t>(mix64(h) >> 32);
    return l;
  }
  // Lattice coordinates of world (x, y).
  void toLattice(double x, double y, double& s, double& t) const {
    s = (cos_a * x - sin_a * y) * inv_cell + off_x;
    t = (sin_a * x + cos_a * y) * inv_cell + off_y;
  }
  // Noise value; with gx, gy: its gradient in world units (1/m).
  double value(double x, double y, double* gx = nullptr, double* gy = nullptr) const {
    double s, t;
    toLattice(x, y, s, t);
    const std::int32_t i = floorToInt(s), j = floorToInt(t);
    const double u = s - i, w = t - j;
    const double su = u * u * u * (u * (u * 6.0 - 15.0) + 10.0);
    const double sw = w * w * w * (w * (w * 6.0 - 15.0) + 10.0);
    const std::uint32_t h00 = key + static_cast<std::uint32_t>(i) * kHashStepI +
                              static_cast<std::uint32_t>(j) * kHashStepJ;
    const double a = hashToSigned(finalizeHash(h00));
    const double b = hashToSigned(finalizeHash(h00 + kHashStepI));
    const double c = hashToSigned(finalizeHash(h00 + kHashStepJ));
    const double d = hashToSigned(finalizeHash(h00 + kHashStepI + kHashStepJ));
    const double k = a - b - c + d;
    if (gx != nullptr) {
      const double dsu = 30.0 * u * u * (u - 1.0) * (u - 1.0);
      const double dsw = 30.0 * w * w * (w - 1.0) * (w - 1.0);
      const double ds = dsu * ((b - a) + k * sw) * inv_cell;  // d n / d(world x') rotated
      const double dt = dsw * ((c - a) + k * su) * inv_cell;
      // (s, t) = R (x, y): grad_xy = R^T grad_st.
      *gx = cos_a * ds + sin_a * dt;
      *gy = -sin_a * ds + cos_a * dt;
    }
    return a + (b - a) * su + (c - a) * sw + k * su * sw;
  }
};

// Heightfield z = h(x, y) = sum_k amp_k n_k(x, y), metres; |h| <= maxAbsHeight(),
// |grad h| <= slopeBound(), |second derivative along any unit direction| <= curvatureBound() (1/m).
class Terrain {
 public:
  static constexpr int kOctaves = 4;
  Terrain() = default;
  // Octave k has cell largest_cell_m / 2^k and amplitude relief_m * w_k, sum w_k = 1.
  Terrain(double relief_m, double largest_cell_m, std::uint64_t seed) {
    static constexpr double kWeights[kOctaves] = {0.55, 0.27, 0.12, 0.06};
    double cell = largest_cell_m;
    for (int k = 0; k < kOctaves; ++k, cell *= 0.5) {
      const NoiseLayer l = NoiseLayer::make(cell, seed, 100 + static_cast<std::uint64_t>(k));
      const double amp = relief_m * kWeights[k];
      ca_[k] = l.cos_a;
      sa_[k] = l.sin_a;
      ic_[k] = l.inv_cell;
      ox_[k] = l.off_x;
      oy_[k] = l.off_y;
      key_[k] = l.key;
      amp_[k] = amp;
      max_abs_ += amp;
      slope_bound_ += amp * kValueNoiseSlopeBound / cell;
      curvature_bound_ += amp * kValueNoiseCurvatureBound / (cell * cell);
    }
  }
  double height(double x, double y) const {
    double gx, gy;
    return height(x, y, gx, gy);
  }
  // The octaves are a structure of arrays so the loop vectorises (SSE2, 2 doubles).
  double height(double x, double y, double& gx, double& gy) const {
    double h[kOctaves], hx[kOctaves], hy[kOctaves];
    for (int k = 0; k < kOctaves; ++k) {
      const double s = (ca_[k] * x - sa_[k] * y) * ic_[k] + ox_[k];
      const double t = (sa_[k] * x + ca_[k] * y) * ic_[k] + oy_[k];
      const std::int32_t i = floorToInt(s), j = floorToInt(t);
      const double u = s - i, w = t - j;
      const double su = u * u * u * (u * (u * 6.0 - 15.0) + 10.0);
      const double sw = w * w * w * (w * (w * 6.0 - 15.0) + 10.0);
      const double dsu = 30.0 * u * u * (u - 1.0) * (u - 1.0);
      const double dsw = 30.0 * w * w * (w - 1.0) * (w - 1.0);
      const std::uint32_t h00 = key_[k] + static_cast<std::uint32_t>(i) * kHashStepI +
                                static_cast<std::uint32_t>(j) * kHashStepJ;
      const double a = hashToSigned(finalizeHash(h00));
      const double b = hashToSigned(finalizeHash(h00 + kHashStepI));
      const double c = hashToSigned(finalizeHash(h00 + kHashStepJ));
      const double d = hashToSigned(finalizeHash(h00 + kHashStepI + kHashStepJ));
      const double q = a - b - c + d;
      const double ds = amp_[k] * dsu * ((b - a) + q * sw) * ic_[k];  // along the lattice s axis
      const double dt = amp_[k] * dsw * ((c - a) + q * su) * ic_[k];
      // (s, t) = R (x, y) / cell: grad_xy = R^T grad_st.
      hx[k] = ca_[k] * ds + sa_[k] * dt;
      hy[k] = -sa_[k] * ds + ca_[k] * dt;
      h[k] = amp_[k] * (a + (b - a) * su + (c - a) * sw + q * su * sw);
    }
    gx = (hx[0] + hx[1]) + (hx[2] + hx[3]);
    gy = (hy[0] + hy[1]) + (hy[2] + hy[3]);
    return (h[0] + h[1]) + (h[2] + h[3]);
  }
  double maxAbsHeight() const { return max_abs_; }
  double slopeBound() const { return slope_bound_; }
  double curvatureBound() const { return curvature_bound_; }

 private:
  alignas(64) double ca_[kOctaves] = {}, sa_[kOctaves] = {}, ic_[kOctaves] = {};
  alignas(64) double ox_[kOctaves] = {}, oy_[kOctaves] = {}, amp_[kOctaves] = {};
  alignas(64) std::uint32_t key_[kOctaves] = {};
  double max_abs_ = 0.0;
  double slope_bound_ = 0.0;
  double curvature_bound_ = 0.0;
};

// Cubic smooth step from 0 at x <= 0 to 1 at x >= 1.
inline double smooth01(double x) {
  const double t = std::clamp(x, 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}

// Weight of a detail `ratio` pixel footprints wide: 0 when it would alias (<= 1.5 footprints),
// 1 when it is well resolved (>= 3 footprints).
inline double bandWeight(double ratio) { return smooth01((ratio - 1.5) * (1.0 / 1.5)); }

// Up to kMaxLayers value-noise layers evaluated together in float (structure of arrays; the loop
// vectorises with plain SSE2). Float keeps the lattice fraction to < 1e-3 cells for the finest
// layers within ~1 km of the origin (loop_length_m is bounded accordingly).
class NoiseBank {
 public:
  static constexpr int kMaxLayers = 16;
  int size() const { return n_; }
  void add(const NoiseLayer& l) {
    ca_[n_] = static_cast<float>(l.cos_a);
    sa_[n_] = static_cast<float>(l.sin_a);
    ic_[n_] = static_cast<float>(l.inv_cell);
    // Offsets wrapped into [0, 1024) lattice units: only the fraction and the hash input matter.
    ox_[n_] = static_cast<float>(std::fmod(l.off_x, 1024.0));
    oy_[n_] = static_cast<float>(std::fmod(l.off_y, 1024.0));
    key_[n_] = l.key;
    ++n_;
  }
  // Values in [-1, 1] of layers [0, n) at world (x, y); writes out[0 .. n rounded up to 4).
  void values(double xd, double yd, int n, float* out) const {
    const float x = static_cast<float>(xd), y = static_cast<float>(yd);
    const int n4 = std::min((n + 3) & ~3, kMaxLayers);
    for (int k = 0; k < n4; ++k) {
      const float s = (ca_[k] * x - sa_[k] * y) * ic_[k] + ox_[k];
      const float t = (sa_[k] * x + ca_[k] * y) * ic_[k] + oy_[k];
      std::int32_t i = static_cast<std::int32_t>(s);
      i -= s < static_cast<float>(i) ? 1 : 0;
      std::int32_t j = static_cast<std::int32_t>(t);
      j -= t < static_cast<float>(j) ? 1 : 0;
      const float u = s - static_cast<float>(i), w = t - static_cast<float>(j);
      const float su = u * u * u * (u * (u * 6.0f - 15.0f) + 10.0f);
      const float sw = w * w * w * (w * (w * 6.0f - 15.0f) + 10.0f);
      const std::uint32_t h = key_[k] + static_cast<std::uint32_t>(i) * kHashStepI +
                              static_cast<std::uint32_t>(j) * kHashStepJ;
      const auto lat = [](std::uint32_t v) {
        return static_cast<float>(static_cast<std::int32_t>(finalizeHash(v) >> 8));
      };
      const float a = lat(h), b = lat(h + kHashStepI), c = lat(h + kHashStepJ),
                  d = lat(h + kHashStepI + kHashStepJ);
      out[k] =
          (a + (b - a) * su + (c - a) * sw + (a - b - c + d) * su * sw) * (2.0f / 16777216.0f) -
          1.0f;
    }
  }

 private:
  alignas(64) float ca_[kMaxLayers] = {}, sa_[kMaxLayers] = {}, ic_[kMaxLayers] = {};
  alignas(64) float ox_[kMaxLayers] = {}, oy_[kMaxLayers] = {};
  alignas(64) std::uint32_t key_[kMaxLayers] = {};
  int n_ = 0;
};

// Albedo in grey levels around 128: equal-energy octaves of value noise from 4 m down to 4 mm,
// thresholded-noise patches (curved edges, blobs) and random rectangles (straight edges, L and X
// corners) at several scales. Every term is band-limited by the pixel footprint fp_m (metres on
// the ground): details that would alias fade to their mean, edges are ramps at least one
// footprint wide (box-filtered), so a point sample per pixel is alias-free.
class Albedo {
 public:
  Albedo() = default;
  explicit Albedo(std::uint64_t seed) {
    // Noise octaves and patch layers share one bank, sorted coarse to fine.
    std::vector<Layer> layers;
    std::uint64_t salt = 1000;
    for (double cell = 4.0; cell >= 0.004; cell *= 0.5)
      layers.push_back({NoiseLayer::make(cell, seed, salt++), cell, false});
    for (double cell : {6.0, 1.3, 0.3, 0.07, 0.017})
      layers.push_back({NoiseLayer::make(cell, seed, salt++), cell, true});
    std::stable_sort(layers.begin(), layers.end(),
                     [](const Layer& a, const Layer& b) { return a.cell > b.cell; });
    for (const auto& l : layers) {
      bank_.add(l.layer);
      bank_layers_.push_back(l);
    }
    for (double cell : {5.0, 1.1, 0.25, 0.06, 0.015})
      boxes_.push_back({NoiseLayer::make(cell, seed, salt++), cell, false});
  }

  double at(double x, double y, double fp_m) const {
    const double inv_fp = 1.0 / fp_m;
    // Layers finer than 1.5 footprints have zero weight.
    int n = 0;
    while (n < bank_.size() && bank_layers_[static_cast<std::size_t>(n)].cell * inv_fp > 1.5) ++n;
    alignas(64) float noise[NoiseBank::kMaxLayers];
    bank_.values(x, y, n, noise);
    double v = 0.0;
    for (int k = 0; k < n; ++k) {
      const Layer& l = bank_layers_[static_cast<std::size_t>(k)];
      const double ratio = l.cell * inv_fp;  // cell size in footprints
      const double w = bandWeight(ratio);
      if (l.patch) {
        // The noise changes by ~1.5 per cell: a ramp of +-e noise units is ~1.3 e cell metres;
        // e = max(0.04, 0.8 / ratio) keeps it at least a footprint wide.
        const double inv_2e = std::min(12.5, 0.625 * ratio);
        v += 22.0 * w * (2.0 * smooth01(0.5 + noise[k] * inv_2e) - 1.0);
      } else {
        v += 16.0 * w * noise[k];
      }
    }
    for (const auto& b : boxes_) {
      const double ratio = b.cell * inv_fp;
      if (ratio <= 1.5) break;
      v += 30.0 * bandWeight(ratio) * box(b, x, y, ratio);
    }
    return 128.0 + v;
  }

 private:
  struct Layer {
    NoiseLayer layer;
    double cell;
    bool patch;  // thresholded (patches) or plain (octave)
  };
  // A rectangle in about half of the lattice cells, random size, position and sign (+-1 inside,
  // 0 outside); the coverage of a footprint-wide box filter along each axis. `ratio`: the cell
  // size in footprints.
  static double box(const Layer& b, double x, double y, double ratio) {
    double s, t;
    b.layer.toLattice(x, y, s, t);
    const std::int32_t i = floorToInt(s), j = floorToInt(t);
    const std::uint32_t h = hashLattice(i, j, b.layer.key);
    if ((h & 1u) == 0u) return 0.0;
    const double hw = 0.15 + 0.25 * static_cast<double>((h >> 1) & 0xFF) / 255.0;  // half width
    const double hh = 0.15 + 0.25 * static_cast<double>((h >> 9) & 0xFF) / 255.0;
    const double cs = hw + (1.0 - 2.0 * hw) * static_cast<double>((h >> 17) & 0x1F) / 31.0;
    const double ct = hh + (1.0 - 2.0 * hh) * static_cast<double>((h >> 22) & 0x1F) / 31.0;
    const double sign = (h >> 27) & 1u ? 1.0 : -1.0;
    // Fraction of a footprint-wide interval inside an edge `dist` lattice units away.
    auto cover = [ratio](double dist) { return std::clamp(dist * ratio + 0.5, 0.0, 1.0); };
    return sign * cover(hw - std::fabs(s - i - cs)) * cover(hh - std::fabs(t - j - ct));
  }

  NoiseBank bank_;
  std::vector<Layer> bank_layers_, boxes_;
};

}  // namespace svslam::drivers::synth
