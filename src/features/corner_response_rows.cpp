#include "features/corner_response_rows.hpp"

#include <algorithm>

namespace svslam {
namespace {

// Taps of the largest kernel: radius ceil(3 sigma) with sigma <= 10 px (CornerParams::validate).
constexpr int kMaxTaps = 64;

// Horizontal pass of a padded row:
//   out[x] = sum_j c[j] pad[x + 2r - j] = sum_j c[j] in(x - (j - r)).
void horizontal(const simd::FloatRowKernels& k, const float* pad, const std::vector<float>& c,
                float* out, int w) {
  const int r = static_cast<int>(c.size() / 2);
  const float* taps[kMaxTaps];
  for (int j = 0; j <= 2 * r; ++j) taps[j] = pad + 2 * r - j;
  k.convolve(taps, c.data(), 2 * r + 1, out, w);
}

}  // namespace

CornerResponseRows::CornerResponseRows(int width, const std::vector<float>& kd,
                                       const std::vector<float>& kg,
                                       const std::vector<float>& ki)
    : kern_(simd::floatRowKernels()),
      w_(width),
      rd_(static_cast<int>(kd.size() / 2)),
      ri_(static_cast<int>(ki.size() / 2)),
      stride_((static_cast<std::size_t>(width) + 15) / 16 * 16 + 16),
      kd_(kd),
      kg_(kg),
      ki_(ki) {
  const std::size_t w = static_cast<std::size_t>(width);
  pad_.resize(w + 2 * static_cast<std::size_t>(rd_));
  for (auto* ring : {&hd_, &hg_}) ring->resize(stride_ * static_cast<std::size_t>(2 * rd_ + 1));
  for (auto* ring : {&qxx_, &qyy_, &qxy_})
    ring->resize(stride_ * static_cast<std::size_t>(2 * ri_ + 1));
  for (auto* row : {&pxx_, &pyy_, &pxy_}) row->resize(w + 2 * static_cast<std::size_t>(ri_));
  for (auto* row : {&gx_, &gy_, &mxx_, &myy_, &mxy_}) row->resize(w);
}

void CornerResponseRows::filterImageRow(const std::uint8_t* src, int y) {
  float* pad = pad_.data();  // pad[i] = I(clamp(i - rd), y)
  for (int i = 0; i < rd_; ++i) pad[i] = static_cast<float>(src[0]);
  for (int x = 0; x < w_; ++x) pad[x + rd_] = static_cast<float>(src[x]);
  for (int i = 0; i < rd_; ++i) pad[w_ + rd_ + i] = static_cast<float>(src[w_ - 1]);
  horizontal(kern_, pad, kd_, ringRow(hd_, 2 * rd_ + 1, y), w_);
  horizontal(kern_, pad, kg_, ringRow(hg_, 2 * rd_ + 1, y), w_);
}

void CornerResponseRows::vertical(std::vector<float>& ring, const std::vector<float>& c, int y,
                                  int h, float* out) {
  const int slots = static_cast<int>(c.size()), r = slots / 2;
  const float* taps[kMaxTaps];
  for (int j = 0; j < slots; ++j)
    taps[j] = ringRow(ring, slots, std::clamp(y - (j - r), 0, h - 1));
  kern_.convolve(taps, c.data(), slots, out, w_);
}

void CornerResponseRows::integrateRow(std::vector<float>& padded, std::vector<float>& q_ring,
                                      int g) {
  float* p = padded.data();
  for (int i = 0; i < ri_; ++i) {
    p[i] = p[ri_];
    p[w_ + ri_ + i] = p[w_ + ri_ - 1];
  }
  horizontal(kern_, p, ki_, ringRow(q_ring, 2 * ri_ + 1, g), w_);
}

void CornerResponseRows::tensorRow(int g, int h) {
  vertical(hd_, kg_, g, h, gx_.data());  // Ix: kd along x, kg along y
  vertical(hg_, kd_, g, h, gy_.data());  // Iy: kg along x, kd along y
  kern_.products(gx_.data(), gy_.data(), pxx_.data() + ri_, pyy_.data() + ri_, pxy_.data() + ri_,
                 w_);
  integrateRow(pxx_, qxx_, g);
  integrateRow(pyy_, qyy_, g);
  integrateRow(pxy_, qxy_, g);
}

float CornerResponseRows::process(ImageView<const std::uint8_t> image, bool harris, double k,
                                  int y0, int y1, ImageF32& resp) {
  const int h = image.height;
  const int g0 = std::max(0, y0 - ri_), g1 = std::min(h, y1 + ri_);  // tensor rows needed
  int next_image_row = std::max(0, g0 - rd_);
  int next_out = y0;
  float max_r = 0;
  for (int g = g0; g < g1; ++g) {
    // The gradient row g needs hd, hg rows clamp(g - rd .. g + rd): the ring's last 2 rd + 1.
    for (const int last = std::min(h - 1, g + rd_); next_image_row <= last; ++next_image_row)
      filterImageRow(image.row(next_image_row), next_image_row);
    tensorRow(g, h);
    // Output row y needs q rows clamp(y - ri .. y + ri): complete once g reaches min(h-1, y+ri),
    // and still in the ring (its last 2 ri + 1 rows).
    for (; next_out < y1 && std::min(h - 1, next_out + ri_) <= g; ++next_out) {
      vertical(qxx_, ki_, next_out, h, mxx_.data());
      vertical(qyy_, ki_, next_out, h, myy_.data());
      vertical(qxy_, ki_, next_out, h, mxy_.data());
      max_r = kern_.response(mxx_.data(), mxy_.data(), myy_.data(), harris, k,
                            resp.row(next_out), w_, max_r);
    }
  }
  return max_r;
}

}  // namespace svslam
