#pragma once
// The corner response of CornerDetector computed row by row over a stripe of rows, through ring
// buffers that stay in cache (the whole-image passes this replaces wrote and re-read six float
// images per frame).
//
// For an h-row image I, a derivative kernel kd and a smoothing kernel kg of radius rd and an
// integration kernel ki of radius ri, with replicated borders (clamp to [0, h - 1] and to
// [0, w - 1]) and each sum taken in tap order (simd::FloatRowKernels::convolve):
//   hd(y) = kd *x I(y),   hg(y) = kg *x I(y)                        (one image row, horizontal)
//   Ix(y) = sum_j kg[j] hd(clamp(y - (j - rd))),   Iy(y) = sum_j kd[j] hg(clamp(y - (j - rd)))
//   p(y)  = (Ix^2, Iy^2, Ix Iy)(y),   q(y) = ki *x p(y)
//   M(y)  = sum_j ki[j] q(clamp(y - (j - ri))),   R(y) = response(M(y))
// Every value is computed by the same float operations whichever stripe computes it (a stripe
// recomputes the halo rows it needs), so R is identical for any split into stripes, and to the
// separable whole-image passes with the same kernels.
#include <cstdint>
#include <vector>

#include "core/image.hpp"
#include "simd/float_row_kernels.hpp"

namespace svslam {

class CornerResponseRows {
 public:
  // Preallocates the rings for images `width` wide. kd and kg have 2 rd + 1 taps, ki 2 ri + 1
  // (odd lengths, at most 63; copied).
  CornerResponseRows(int width, const std::vector<float>& kd, const std::vector<float>& kg,
                     const std::vector<float>& ki);
  // Writes resp rows [y0, y1) of `image` (width as constructed, 0 <= y0 < y1 <= height);
  // Harris with constant k when `harris`, else Shi-Tomasi. Returns the largest response of
  // these rows, or 0 if none is positive.
  float process(ImageView<const std::uint8_t> image, bool harris, double k, int y0, int y1,
                ImageF32& resp);

 private:
  float* ringRow(std::vector<float>& ring, int slots, int y) {
    return ring.data() + static_cast<std::size_t>(y % slots) * stride_;
  }
  // out = sum_j c[j] row(clamp(y - (j - r))) over the rows of `ring` (slots = 2 r + 1 rows,
  // c of the same length), h the image height.
  void vertical(std::vector<float>& ring, const std::vector<float>& c, int y, int h, float* out);
  void filterImageRow(const std::uint8_t* src, int y);  // hd(y), hg(y) into their rings
  void tensorRow(int g, int h);                         // q(g) from hd, hg rows around g
  // Horizontal ki pass of a padded product row (ri floats each side, filled here) into q.
  void integrateRow(std::vector<float>& padded, std::vector<float>& q_ring, int g);

  const simd::FloatRowKernels& kern_;  // the fastest available row kernels
  int w_, rd_, ri_;
  std::size_t stride_;  // floats between ring rows: w rounded up, plus a cache line (no 4K alias)
  std::vector<float> kd_, kg_, ki_;
  std::vector<float> pad_;             // w + 2 rd: the image row as float, replicated borders
  std::vector<float> hd_, hg_;         // rings of 2 rd + 1 rows
  std::vector<float> gx_, gy_;         // one gradient row each
  std::vector<float> pxx_, pyy_, pxy_;  // w + 2 ri: product rows with replicated borders
  std::vector<float> qxx_, qyy_, qxy_;  // rings of 2 ri + 1 rows
  std::vector<float> mxx_, myy_, mxy_;  // one structure-tensor row each
};

}  // namespace svslam
