#pragma once
// Improved ORB (seed 002, section 2.2.1): FAST 9-16 on an 8-layer scale pyramid with
// non-maximum suppression in position and scale, sub-pixel and continuous-scale refinement,
// intensity-centroid orientation and a steered BRIEF (rBRIEF) 256-bit descriptor.
//
// Pyramid (Table 1). Layer k = 0 .. 2 * num_octaves - 1 in order of scale: even k = c_i, odd
// k = d_i with i = k / 2. Its scale t_k (level-0 px per layer px) is 2^i for c_i and 1.5 * 2^i
// for d_i: 1, 1.5, 2, 3, 4, 6, 8, 12, i.e. sizes w, 2/3 w, 1/2 w, 1/3 w, ... (rounded down:
// c_i is (w >> i) x (h >> i), d_i is ((2w/3) >> i) x ((2h/3) >> i)). d_0 is area-resampled from
// c_0 by 2/3, c_{i+1} from c_i and d_{i+1} from d_i by 1/2 (box filter over each target pixel's
// footprint, the anti-aliasing filter of INTER_AREA). Layer pixel centres map to level 0 as
//   X0 = (x_k + 0.5) t_k - 0.5     (the same for y).
//
// Detection. FAST 9-16 (fast_detector.hpp) with the same threshold on every layer, at least
// kBorderPx from each layer's border. A corner (k, x, y) with score s survives when
//  - in its layer, s beats its 8 neighbours (s > q; an equal neighbour earlier in raster order
//    wins the tie),
//  - in the layer above (k + 1), s >= each of the 9 scores at the 3x3 grid points
//    (x + dx, y + dy) mapped through t_k / t_{k+1}, bilinearly interpolated,
//  - in the layer below (k - 1, k >= 1), s > each of the 9 mapped, interpolated scores.
// That is the 26-neighbourhood test. Below c_0 sits the virtual layer d_{-1} (t = 2/3): its
// scores are FAST 5-8 scores on c_0 at the 3x3 grid; as the seed says, c_0 corners are not
// required to beat them (they only enter the refinement).
//
// Refinement. For each of the layers k - 1, k, k + 1 the 9 scores on the mapped 3x3 grid are
// fitted by least squares with f(u, v) = a + b u + c v + d u^2 + e u v + g v^2 (grid units =
// layer-k pixels); where f is concave its maximum gives a sub-pixel offset (clamped to +-1) and
// a refined score s_j, else the offset is 0 and s_j = the centre score. A parabola through
// (log2 t_j, s_j), j = k - 1, k, k + 1, gives the continuous scale t = 2^u* (u* at its vertex,
// clamped to [log2 t_{k-1}, log2 t_{k+1}]; t_k when it is not concave) and the keypoint score
// s(u*). The position is re-interpolated linearly in log-scale between the sub-pixel maximum of
// layer k and that of the neighbouring layer on the side of u*. The top layer has no layer above:
// it gets the in-layer fit only, t = t_k.
//
// Bucketing. The level-0 image is cut into grid_cols x grid_rows cells; each cell keeps its
// max_per_cell highest-score keypoints. Output is cell by cell (row-major), strongest first.
//
// Orientation (intensity centroid). On detection layer k (unsmoothed) around the detected
// pixel, m_pq = sum over the disc u^2 + v^2 <= r^2 of u^p v^q I(x + u, y + v), and
//   angle = atan2(m01, m10)   radians, image axes (x right, y down; positive = clockwise on
//                             screen), in (-pi, pi].
// The moments are taken about the integer pixel, as in ORB: taking them about the sub-pixel
// position (m10 - dx m00, ...) makes the angle less repeatable, because m00 is large and the
// sub-pixel offsets of FAST maxima are noisy.
//
// Descriptor (rBRIEF). 256 point pairs (p_j, q_j), integer offsets drawn once from an isotropic
// Gaussian N(0, (31/5)^2 px^2) (BRIEF's G II sampling) with a SplitMix64 generator seeded by
// pattern_seed, redrawn when outside the disc of radius 15 (so inside the 31 x 31 patch for any
// rotation) or when p_j = q_j. The pattern is steered by the angle quantised to angle_step_deg:
// R(theta) p with R = [cos -sin; sin cos] in image axes, rounded, one lookup table per angle.
// Bit j (bit j % 64 of word j / 64) is 1 when S(c + R p_j) < S(c + R q_j), S = the detection
// layer smoothed by a Gaussian of blur_sigma_px (radius ceil(2 sigma)), c = the detected pixel.
//
// Preconditions and costs: the extractor is built for one image size; process() allocates
// nothing once the candidate buffer and the caller's output vectors have grown (all scratch is
// kept between frames). Single-threaded and deterministic.
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/image.hpp"
#include "core/status.hpp"

namespace svslam {

struct OrbParams {
  int num_octaves = 4;                // octaves i of the pyramid (c_i and d_i each), 1..4
  int fast_threshold = 20;            // FAST 9-16 threshold t, grey levels, 1..254, every layer
  int orientation_radius_px = 15;     // r of the intensity-centroid disc, layer px, 3..15
  double blur_sigma_px = 2.0;         // Gaussian before the BRIEF tests, layer px, 0.5..4
  int angle_step_deg = 12;            // steering quantisation, degrees, 1..45, divides 360
  std::uint64_t pattern_seed = 2011;  // seeds the 256 BRIEF point pairs
  int grid_cols = 8;                  // bucketing grid over the level-0 image, >= 1
  int grid_rows = 4;                  // >= 1
  int max_per_cell = 32;              // keypoints kept per cell, >= 1
  Status validate() const;
};

struct OrbKeypoint {
  float x_px = 0;       // level-0 column, sub-pixel
  float y_px = 0;       // level-0 row, sub-pixel
  float scale = 1;      // continuous scale t, level-0 px per layer px (2/3 .. 12)
  float size_px = 31;   // diameter of the descriptor patch in level-0 px: 31 * t_layer
  float angle_rad = 0;  // intensity-centroid orientation, image axes, (-pi, pi]
  float score = 0;      // refined FAST score (fitted maximum), grey levels
  int layer = 0;        // detection layer k (0 = c_0, 1 = d_0, 2 = c_1, ...)
  int octave = 0;       // i of c_i / d_i, = layer / 2
};

struct OrbDescriptor {
  std::array<std::uint64_t, 4> words{};  // bit j = test j, in words[j / 64] bit j % 64
  bool operator==(const OrbDescriptor&) const = default;
};

// Number of differing bits, 0..256.
int hammingDistance(const OrbDescriptor& a, const OrbDescriptor& b);

class OrbExtractor {
 public:
  static constexpr int kPatchRadiusPx = 15;  // the 31 x 31 BRIEF patch
  static constexpr int kBorderPx = 16;       // detections keep this far from a layer's border
  static constexpr int kBits = 256;

  OrbExtractor(const OrbParams& params, int width, int height);
  const Status& initStatus() const { return init_status_; }

  // Keypoints and their descriptors (same index) of `image` (width x height). On error both
  // vectors are left empty.
  Status process(ImageView<const std::uint8_t> image, std::vector<OrbKeypoint>& keypoints,
                 std::vector<OrbDescriptor>& descriptors);

  int numLayers() const { return static_cast<int>(layers_.size()); }
  // t_k, level-0 px per layer px; t_{-1} = 2/3 (the virtual layer below c_0).
  static double layerScale(int k);
  // Layer k of the last processed image (unsmoothed).
  ImageView<const std::uint8_t> layer(int k) const;
  // The unrotated test pattern: pair j = (x1, y1, x2, y2), px offsets from the patch centre.
  const std::vector<std::array<std::int8_t, 4>>& pattern() const { return pattern_; }

 private:
  static constexpr std::uint8_t kUnknownScore = 255;  // score not yet computed (FAST: 0..254)
  struct AreaTap {  // one target pixel of an area resampling: sum of w[t] * source[k[t]]
    std::array<int, 3> k{};
    std::array<float, 3> w{};
  };
  struct Layer {
    double scale = 1;
    int source = -1;  // layer it is resampled from
    ImageU8 image, smoothed;
    ImageU8 score;  // lazily filled FAST 9-16 scores, 255 = not computed yet
    std::array<std::ptrdiff_t, 16> circle{};  // FAST 9-16 circle as pointer offsets
    std::vector<AreaTap> taps_x, taps_y;
  };
  struct Candidate {
    int layer, x, y;
    float score;          // FAST score, then refined
    float x0, y0, scale;  // refined level-0 position and scale
    int cell;
  };

  void resampleLayer(int k);
  void smoothLayer(int k);
  int lazyScore(int k, int x, int y);  // k = -1: FAST 5-8 on c_0
  // An upper bound of layer k's score (k >= 0) without computing it where it is not needed:
  // the cached score; threshold - 1 for a pixel the scan tested and found no corner (a pixel
  // that is not a corner at t scores below t); the score itself elsewhere.
  int scoreBound(int k, int x, int y);
  float sampleScore(int j, double x, double y);
  // Whether layer j's grid point (gx, gy) (layer-k px of candidate c) can suppress c: its
  // bilinear score bound first (monotone in the four scores), the score only when the bound
  // would suppress. Suppresses when the score > s, or >= s with or_equal.
  bool suppresses(const Candidate& c, int j, int gx, int gy, bool or_equal);
  void sampleGrid(const Candidate& c, int j, float v[9]);
  bool suppressAndRefine(Candidate& c);
  float orientation(const Layer& l, int x, int y) const;
  OrbDescriptor describe(const Layer& l, int x, int y, float angle_rad) const;

  OrbParams params_;
  Status init_status_;
  int width_ = 0, height_ = 0;
  std::vector<Layer> layers_;
  ImageU8 score58_;  // lazily filled FAST 5-8 scores on c_0 (the virtual layer d_{-1})
  std::array<std::ptrdiff_t, 8> circle8_{};
  ImageF32 tmp_;
  std::vector<float> gauss_, row_in_;  // smoothing kernel, padded source row
  std::vector<int> disc_half_width_;   // orientation disc: |u| <= half_width[|v|]
  std::vector<std::array<std::int8_t, 4>> pattern_;
  std::vector<std::array<std::int8_t, 4>> rotated_;  // angle bin b: pairs b * kBits ...
  std::vector<Candidate> candidates_;
};

}  // namespace svslam
