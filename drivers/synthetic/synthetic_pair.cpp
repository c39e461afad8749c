#include "drivers/synthetic/synthetic_pair.hpp"

#include <cmath>
#include <random>
#include <vector>

namespace svslam::drivers {
namespace {

// Value noise: bilinear interpolation of a seeded lattice, summed over octaves (periods 32..2 px).
class Texture {
 public:
  Texture(std::uint32_t seed, int salt) {
    std::mt19937 rng(seed * 7919u + static_cast<std::uint32_t>(salt));
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    lattice_.resize(kN * kN);
    for (auto& v : lattice_) v = u(rng);
  }
  // Intensity at surface coordinates (s, t) in pixels.
  float at(float s, float t) const {
    float v = 0.0f, amp = 60.0f;
    for (float period = 32.0f; period >= 2.0f; period *= 0.5f, amp *= 0.7f)
      v += amp * lerp(s / period, t / period);
    return std::fmin(255.0f, std::fmax(0.0f, 128.0f + v));
  }

 private:
  static constexpr int kN = 256;
  float lerp(float s, float t) const {
    const float fs = std::floor(s), ft = std::floor(t);
    const int i = static_cast<int>(fs) & (kN - 1), j = static_cast<int>(ft) & (kN - 1);
    const float a = s - fs, b = t - ft;
    auto L = [&](int ii, int jj) {
      return lattice_[static_cast<std::size_t>((jj & (kN - 1)) * kN + (ii & (kN - 1)))];
    };
    return (1 - a) * (1 - b) * L(i, j) + a * (1 - b) * L(i + 1, j) + (1 - a) * b * L(i, j + 1) +
           a * b * L(i + 1, j + 1);
  }
  std::vector<float> lattice_;
};

}  // namespace

Status SyntheticPairParams::validate() const {
  if (width < 32 || width > 8192 || height < 32 || height > 8192)
    return Status::invalidArgument("synthetic pair size must be in 32..8192");
  if (!std::isfinite(d_far_px) || d_far_px < 0)
    return Status::invalidArgument("d_far_px must be finite and >= 0");
  if (!std::isfinite(slope) || std::fabs(slope) >= 0.5f)
    return Status::invalidArgument("|slope| must be < 0.5");
  if (!std::isfinite(d_near_px) ||
      d_near_px <= d_far_px + std::fabs(slope) * static_cast<float>(width))
    return Status::invalidArgument("d_near_px must exceed every background disparity");
  if (d_near_px >= static_cast<float>(width) / 2)
    return Status::invalidArgument("d_near_px must be < width / 2");
  return Status::ok();
}

Result<SyntheticPair> makeSyntheticPair(const SyntheticPairParams& p) {
  if (Status s = p.validate(); !s) return s;
  const Texture bg(p.seed, 1), box(p.seed, 2);
  const int W = p.width, H = p.height;
  const int bx0 = W / 3, bx1 = 2 * W / 3, by0 = H / 4, by1 = 3 * H / 4;  // box in left coordinates
  auto bgDisp = [&](float xl) { return p.d_far_px + p.slope * xl; };
  SyntheticPair out;
  out.left.resize(W, H);
  out.right.resize(W, H);
  out.gt_disparity_px.resize(W, H);
  out.nonocc_mask.resize(W, H);
  for (int y = 0; y < H; ++y) {
    const bool box_row = y >= by0 && y < by1;
    for (int x = 0; x < W; ++x) {
      const bool on_box = box_row && x >= bx0 && x < bx1;
      // Texture coordinates live on the surfaces (left-image x), so both views see the same paint.
      out.left(x, y) = static_cast<std::uint8_t>(std::lround(on_box ? box.at(x, y) : bg.at(x, y)));
      const float d = on_box ? p.d_near_px : bgDisp(static_cast<float>(x));
      out.gt_disparity_px(x, y) = d;
      // Visible in the right view unless outside it or hidden by the box.
      const float xr = static_cast<float>(x) - d;
      const bool hidden = !on_box && box_row && xr >= bx0 - p.d_near_px && xr < bx1 - p.d_near_px;
      out.nonocc_mask(x, y) = (xr >= 0.0f && !hidden) ? 255 : 0;
    }
    for (int xr = 0; xr < W; ++xr) {
      // The box covers right pixels [bx0 - d_near, bx1 - d_near); elsewhere the background:
      // xl - (d_far + slope xl) = xr  ->  xl = (xr + d_far) / (1 - slope).
      const float xb = static_cast<float>(xr) + p.d_near_px;
      float v;
      if (box_row && xb >= bx0 && xb < bx1) {
        v = box.at(xb, static_cast<float>(y));
      } else {
        v = bg.at((static_cast<float>(xr) + p.d_far_px) / (1.0f - p.slope), static_cast<float>(y));
      }
      out.right(xr, y) = static_cast<std::uint8_t>(std::lround(v));
    }
  }
  return out;
}

}  // namespace svslam::drivers
