// OrbExtractor's scale-space part (seed 002 sec 2.2.1, BRISK-style): FAST scores computed lazily
// per layer, bilinear sampling of a neighbouring layer's scores, and the 3x3x3 non-maximum
// suppression with quadratic refinement in position and scale.
#include <algorithm>
#include <cmath>

#include "features/fast_detector.hpp"
#include "features/orb_extractor.hpp"

namespace svslam {
namespace {

// Least-squares quadratic f(u, v) = a + b u + c v + d u^2 + e u v + g v^2 over the 3x3 grid
// u, v in {-1, 0, 1}, samples s[(v + 1) * 3 + u + 1]. The basis 1, u, v, uv, u^2 - 2/3,
// v^2 - 2/3 is orthogonal on the grid, so each coefficient is a normalised inner product. Where
// the Hessian [2d e; e 2g] is negative definite the maximum is at -H^-1 (b, c), clamped to +-1;
// elsewhere the centre sample is returned with a zero offset.
struct QuadMax {
  double du = 0, dv = 0, value = 0;
};

QuadMax fitQuadratic3x3(const float s[9]) {
  double sum = 0, su = 0, sv = 0, suv = 0, suu = 0, svv = 0;
  for (int j = -1; j <= 1; ++j)
    for (int i = -1; i <= 1; ++i) {
      const double f = s[(j + 1) * 3 + i + 1];
      sum += f;
      su += i * f;
      sv += j * f;
      suv += i * j * f;
      suu += (i * i - 2.0 / 3.0) * f;
      svv += (j * j - 2.0 / 3.0) * f;
    }
  const double b = su / 6, c = sv / 6, e = suv / 4, d = suu / 2, g = svv / 2;
  const double a = sum / 9 - 2.0 / 3.0 * (d + g);
  QuadMax q;
  q.value = s[4];
  const double det = 4 * d * g - e * e;
  if (!(d < 0 && det > 0)) return q;
  q.du = std::clamp((e * c - 2 * g * b) / det, -1.0, 1.0);
  q.dv = std::clamp((e * b - 2 * d * c) / det, -1.0, 1.0);
  q.value = a + b * q.du + c * q.dv + d * q.du * q.du + e * q.du * q.dv + g * q.dv * q.dv;
  return q;
}

// Bilinear interpolation of score(x, y) (integer pixels of a w x h layer) at (x, y), clamped to
// the layer. With non-negative weights and rounding monotone, a score bound in place of the
// score gives a bound of the interpolated score, operation by operation.
template <class Score>
float bilinearScore(int w, int h, double x, double y, Score score) {
  x = std::clamp(x, 0.0, w - 1.0);
  y = std::clamp(y, 0.0, h - 1.0);
  const int x0 = std::min(static_cast<int>(x), w - 2), y0 = std::min(static_cast<int>(y), h - 2);
  const float fx = static_cast<float>(x - x0), fy = static_cast<float>(y - y0);
  const float top = (1 - fx) * score(x0, y0) + fx * score(x0 + 1, y0);
  const float bottom = (1 - fx) * score(x0, y0 + 1) + fx * score(x0 + 1, y0 + 1);
  return (1 - fy) * top + fy * bottom;
}

}  // namespace

int OrbExtractor::lazyScore(int k, int x, int y) {
  if (k < 0) {
    const ImageU8& img = layers_[0].image;
    if (x < 1 || y < 1 || x >= img.width() - 1 || y >= img.height() - 1) return 0;
    std::uint8_t& s = score58_(x, y);
    if (s == kUnknownScore) s = static_cast<std::uint8_t>(fastScore8(img.row(y) + x, circle8_));
    return s;
  }
  Layer& l = layers_[static_cast<std::size_t>(k)];
  if (x < 3 || y < 3 || x >= l.image.width() - 3 || y >= l.image.height() - 3) return 0;
  std::uint8_t& s = l.score(x, y);
  if (s == kUnknownScore) s = static_cast<std::uint8_t>(fastScore16(l.image.row(y) + x, l.circle));
  return s;
}

int OrbExtractor::scoreBound(int k, int x, int y) {
  Layer& l = layers_[static_cast<std::size_t>(k)];
  const int w = l.image.width(), h = l.image.height();
  if (x < 3 || y < 3 || x >= w - 3 || y >= h - 3) return 0;  // as lazyScore
  const std::uint8_t s = l.score(x, y);
  if (s != kUnknownScore) return s;
  // The scan (process) tested every pixel kBorderPx (>= 3) from the border and cached the
  // score of each corner, so an unknown score there is a non-corner's.
  if (x >= kBorderPx && y >= kBorderPx && x < w - kBorderPx && y < h - kBorderPx)
    return params_.fast_threshold - 1;
  return lazyScore(k, x, y);
}

// Bilinear interpolation of layer j's scores at (x, y) in layer-j px (clamped to the layer).
float OrbExtractor::sampleScore(int j, double x, double y) {
  const Layer& l = layers_[static_cast<std::size_t>(j)];
  return bilinearScore(l.image.width(), l.image.height(), x, y,
                       [&](int u, int v) { return lazyScore(j, u, v); });
}

// Scores of layer j (k - 1, k, k + 1; -1 = FAST 5-8 on c_0) at the 3x3 grid of layer-k pixels
// around the candidate, mapped through x_j = (x_k + 0.5) t_k / t_j - 0.5.
void OrbExtractor::sampleGrid(const Candidate& c, int j, float v[9]) {
  const double ratio = layerScale(c.layer) / layerScale(j);
  for (int dv = -1; dv <= 1; ++dv)
    for (int du = -1; du <= 1; ++du) {
      float& out = v[(dv + 1) * 3 + du + 1];
      if (j == c.layer || j < 0)
        out = static_cast<float>(lazyScore(j, c.x + du, c.y + dv));
      else
        out = sampleScore(j, (c.x + du + 0.5) * ratio - 0.5, (c.y + dv + 0.5) * ratio - 0.5);
    }
}

bool OrbExtractor::suppresses(const Candidate& c, int j, int gx, int gy, bool or_equal) {
  const float s = c.score;
  if (j == c.layer) {
    const float bound = static_cast<float>(scoreBound(j, gx, gy));
    if (bound < s || (!or_equal && bound == s)) return false;
    const float q = static_cast<float>(lazyScore(j, gx, gy));
    return q > s || (or_equal && q == s);
  }
  const Layer& l = layers_[static_cast<std::size_t>(j)];
  const double ratio = layerScale(c.layer) / layerScale(j);
  const double x = (gx + 0.5) * ratio - 0.5, y = (gy + 0.5) * ratio - 0.5;
  // sampleScore's interpolation with bounds in place of scores: >= its value.
  const float bound = bilinearScore(l.image.width(), l.image.height(), x, y,
                                    [&](int u, int v) { return scoreBound(j, u, v); });
  if (bound < s || (!or_equal && bound == s)) return false;
  const float q = sampleScore(j, x, y);
  return q > s || (or_equal && q == s);
}

bool OrbExtractor::suppressAndRefine(Candidate& c) {
  const int k = c.layer;
  const bool has_above = k + 1 < numLayers();
  // Non-maximum suppression first, on bounds (most candidates of a textured image lose to a
  // neighbour, and most of their neighbours are no corners): the same decisions as comparing
  // every score, without computing the scores that cannot decide.
  for (int i = 0; i < 9; ++i) {
    if (i == 4) continue;
    // Ties: first in raster order wins.
    if (suppresses(c, k, c.x + i % 3 - 1, c.y + i / 3 - 1, i < 4)) return false;
  }
  if (has_above)
    for (int i = 0; i < 9; ++i)
      if (suppresses(c, k + 1, c.x + i % 3 - 1, c.y + i / 3 - 1, false)) return false;
  if (k > 0)  // k = 0: the virtual layer d_{-1} below is not a suppressor
    for (int i = 0; i < 9; ++i)
      if (suppresses(c, k - 1, c.x + i % 3 - 1, c.y + i / 3 - 1, true)) return false;
  // A maximum: the scores of the three grids for the refinement.
  float in[9], above[9], below[9];
  sampleGrid(c, k, in);
  if (has_above) sampleGrid(c, k + 1, above);
  sampleGrid(c, k - 1, below);

  const double tk = layerScale(k);
  auto level0 = [&](int p, double offset) { return (p + offset + 0.5) * tk - 0.5; };
  const QuadMax qk = fitQuadratic3x3(in);
  double x0 = level0(c.x, qk.du), y0 = level0(c.y, qk.dv), score = qk.value, u = 0;
  if (has_above) {
    // Parabola f(h) = s_k + B h + A h^2 in h = log2 t - log2 t_k through the three refined
    // scores at h0 < 0 (below) and h2 > 0 (above).
    const QuadMax qb = fitQuadratic3x3(below), qa = fitQuadratic3x3(above);
    const double h0 = std::log2(layerScale(k - 1) / tk), h2 = std::log2(layerScale(k + 1) / tk);
    const double e0 = qb.value - qk.value, e2 = qa.value - qk.value;
    const double det = h0 * h2 * (h0 - h2);
    const double a = (e0 * h2 - e2 * h0) / det, b = (e2 * h0 * h0 - e0 * h2 * h2) / det;
    if (a < 0) {
      u = std::clamp(-b / (2 * a), h0, h2);
      score = qk.value + b * u + a * u * u;
      const QuadMax& qn = u > 0 ? qa : qb;
      const double w = u > 0 ? u / h2 : u / h0;  // 0 at layer k, 1 at the neighbour layer
      x0 += w * (level0(c.x, qn.du) - x0);
      y0 += w * (level0(c.y, qn.dv) - y0);
    }
  }
  c.x0 = static_cast<float>(x0);
  c.y0 = static_cast<float>(y0);
  c.scale = static_cast<float>(tk * std::exp2(u));
  c.score = static_cast<float>(score);
  return true;
}

}  // namespace svslam
