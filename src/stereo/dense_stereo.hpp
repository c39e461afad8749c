#pragma once
// Dense stereo by local correlation (seed 001 sec 3.1, seed 000 "dense pixel-based stereo").
//
// Input: a rectified grey pair (left, right), same size. Output: for every left pixel either a
// sub-pixel disparity d = x_left - x_right in pixels with its standard deviation sigma_d, or
// +inf (invalid). Steps, all on integer costs (bit-exact across SIMD backends and stripes):
//  1. per-pixel cost C(x, y, d), d in [min_disp, max_disp):
//     census: Hamming distance of the census words (window census_w x census_h, bit set when a
//             neighbour is darker than the centre);
//     sad:    |L'(x, y) - R'(x - d, y)| on 8-bit images, L', R' optionally prefiltered
//             (x-Sobel clipped to +-cap, or mean removal clipped to +-cap, as OpenCV BM does).
//  2. aggregation over a window_w x window_h box with running sums (vertical running sum per
//     column, then a horizontal box), image borders replicated;
//  3. winner-take-all over d (smallest d on ties), candidates restricted to x - d >= 0;
//  4. filters: texture (mean central-difference gradient |I(x+1)-I(x-1)|/2 over the window
//     below texture_threshold -> invalid), uniqueness (best * (100 + u) >= 100 * second best,
//     second best taken at |d - d_best| > 1, and invalid when there is no such candidate),
//     reverse correlation (left-right check:
//     the right image's own WTA on the same costs must agree within lr_max_diff);
//  5. sub-pixel: parabola through the costs at d-1, d, d+1:
//        delta = (c- - c+) / (2 (c- + c+ - 2 c0)),  |delta| <= 1/2,
//     curvature kappa = (c- + c+ - 2 c0) / window area, sigma_d = sigma_model(kappa).
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/aligned_buffer.hpp"
#include "core/executor.hpp"
#include "core/image.hpp"
#include "core/status.hpp"
#include "simd/stereo_kernels.hpp"
#include "stereo/sigma_model.hpp"

namespace svslam {

enum class MatchingCost { kCensus, kSad };
enum class SadPrefilter { kNone, kMeanRemoval, kXSobel };

const char* toString(MatchingCost c);
const char* toString(SadPrefilter p);
bool parseMatchingCost(const std::string& s, MatchingCost& out);
bool parseSadPrefilter(const std::string& s, SadPrefilter& out);

struct DenseStereoParams {
  MatchingCost cost = MatchingCost::kCensus;
  int census_w = 9;  // census window width, px, odd >= 3, census_w * census_h - 1 <= 64
  int census_h = 7;  // census window height, px, odd >= 3
  int window_w = 9;  // aggregation window width, px, odd, 1..31
  int window_h = 9;  // aggregation window height, px, odd, 1..31
  SadPrefilter prefilter = SadPrefilter::kXSobel;  // SAD only
  int prefilter_cap = 31;   // clip of the prefiltered value, grey levels, 1..63
  int prefilter_size = 9;   // mean-removal window, px, odd, 3..21
  int min_disp = 0;         // smallest disparity searched, px, >= 0
  int max_disp = 64;        // one past the largest disparity searched, px; max - min in 1..1024
  int uniqueness_pct = 10;  // 0 disables; best must beat the second best by this many percent
  float texture_threshold = 0.0f;  // grey levels per px of mean |dI/dx|; 0 disables
  bool lr_check = true;            // reverse correlation
  int lr_max_diff = 1;             // px, >= 0, allowed |d_left - d_right|
  bool subpixel = true;            // parabola fit; false gives integer disparities
  int num_stripes = 1;             // row stripes processed as independent tasks, 1..256
  simd::Backend backend = simd::Backend::kAuto;
  // Census in byte planes when the backend has those kernels (faster); false forces the 64-bit
  // word layout (the one AVX-512 and NEON use). Same results either way (tests compare them).
  bool census_byte_planes = true;
  SigmaModel sigma_model = SigmaModel::defaultCensus();

  // Empty status when every field is in range; otherwise names the offending field.
  Status validate() const;
  int numDisp() const { return max_disp - min_disp; }
  // Largest per-pixel cost before aggregation.
  int maxPixelCost() const;
};

struct DenseStereoStats {
  int valid = 0;         // pixels with a disparity
  int no_candidate = 0;  // x < min_disp: no disparity can be searched
  int low_texture = 0;
  int not_unique = 0;
  int lr_inconsistent = 0;
  const char* backend = "";
};

struct DisparityResult {
  ImageF32 disparity_px;  // +inf where invalid
  ImageF32 sigma_d_px;    // +inf where invalid
  ImageF32 curvature;     // kappa of the peak (0 when no parabola could be fitted); +inf invalid
  DenseStereoStats stats;
};

class DenseStereo {
 public:
  // Validates params and preallocates every workspace for width x height images.
  DenseStereo(const DenseStereoParams& params, int width, int height);
  ~DenseStereo();
  DenseStereo(const DenseStereo&) = delete;
  DenseStereo& operator=(const DenseStereo&) = delete;

  // The constructor's verdict: not ok when params or the size are invalid.
  const Status& initStatus() const { return init_status_; }
  const DenseStereoParams& params() const { return params_; }

  // Computes the disparity of `left` against `right` (grey, both width x height). `out` is
  // resized on first use only. Tasks (row stripes) run through `executor`; the result does not
  // depend on the executor or on num_stripes.
  Status process(ImageView<const std::uint8_t> left, ImageView<const std::uint8_t> right,
                 DisparityResult& out, Executor& executor);
  Status process(ImageView<const std::uint8_t> left, ImageView<const std::uint8_t> right,
                 DisparityResult& out);
  // Sizes out's images for this stage's size as process() does: allocated (and zeroed, so every
  // page is touched) once, ahead of the first frame.
  void prepareOutput(DisparityResult& out) const;

 private:
  struct Stripe;
  void padImage(ImageView<const std::uint8_t> src, ImageU8& dst, int y0, int y1) const;
  void prepareRows(Stripe& s);  // census or prefilter rows [s.y0, s.y1) of both images
  void matchRows(Stripe& s, DisparityResult& out);
  std::uint8_t* ringPlane(Stripe& s, int row, int i) const;
  // Byte-plane census of image row `row` (left at [0], right at [1]; plane j at + j * row_stride_,
  // x = 0 at + right_pad_), computed into the stripe's scratch when not already there.
  void censusPlanesRow(Stripe& s, int row, std::uint8_t* (&out)[2]) const;
  void computeCostPlane(Stripe& s, int row, int i) const;
  void ensureCostRow(Stripe& s, int row) const;  // all planes of a row present in the ring

  DenseStereoParams params_;
  Status init_status_;
  int width_ = 0;
  int height_ = 0;
  int pad_x_ = 0;  // padding of the padded grey images
  int pad_y_ = 0;
  int right_pad_ = 0;               // left padding (elements) of right census / prefiltered rows
  std::ptrdiff_t cost_stride_ = 0;  // elements per disparity plane
  std::ptrdiff_t ring_stride_ = 0;  // bytes per uint8 cost plane in the ring
  std::ptrdiff_t agg_stride_ = 0;   // elements per aggregated-cost row
  const simd::StereoKernels* k_ = nullptr;
  bool census_planes_ = false;  // census in byte planes (backends with censusPlanes kernels)
  int census_nplanes_ = 8;      // byte planes holding census bits: ceil((w h - 1) / 8)

  ImageU8 padded_left_, padded_right_;
  AlignedBuffer<std::uint64_t> census_left_, census_right_;  // rows of stride row_stride_
  AlignedBuffer<std::uint8_t> filt_left_, filt_right_;       // SAD rows of stride row_stride_
  std::ptrdiff_t row_stride_ = 0;
  std::vector<std::unique_ptr<Stripe>> stripes_;
  std::vector<float> sigma_by_denom_;  // sigma_model at kappa = v / window area, v = 0 .. max
};

}  // namespace svslam
