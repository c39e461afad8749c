#pragma once
// A seeded synthetic rectified stereo pair with exact ground truth, so that `svslam disparity`
// runs on a fresh machine with no data and no camera, and tests have a known answer.
//
// Scene: a textured background plane slanted in x (disparity from d_far to d_far + slope * W)
// and a textured fronto-parallel box (disparity d_near) in the middle third. Texture: seeded
// multi-octave value noise in [0, 255]. The right image is rendered by ray casting each right
// pixel into the scene (nearest surface wins), so occlusions are real; the left ground truth
// marks pixels hidden in the right view as occluded (mask 0).
#include <cstdint>

#include "core/image.hpp"
#include "core/status.hpp"

namespace svslam::drivers {

struct SyntheticPairParams {
  int width = 640;          // px, 32..8192
  int height = 480;         // px, 32..8192
  float d_far_px = 8.0f;    // background disparity at x = 0, px, >= 0
  float slope = 0.02f;      // background disparity change per pixel of x, px/px, |slope| < 0.5
  float d_near_px = 40.0f;  // box disparity, px, > d_far
  std::uint32_t seed = 1;
  Status validate() const;
};

struct SyntheticPair {
  ImageU8 left, right;
  ImageF32 gt_disparity_px;  // left view, every pixel known
  ImageU8 nonocc_mask;       // 255 = visible in the right image
};

Result<SyntheticPair> makeSyntheticPair(const SyntheticPairParams& p);

}  // namespace svslam::drivers
