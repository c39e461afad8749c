#pragma once
// Frame-to-frame tracking of a small appearance patch in the left image (monocular frames: the
// corners tracked toward bearing-only initialisation and toward the two-view start). A template
// is the (2h+1)^2 grey patch centred on the corner, re-sampled at its sub-pixel position after
// every match (it follows the corner).
#include <cstdint>

#include "core/image.hpp"

namespace svslam {

// The (2h+1)^2 patch of `img` centred on sub-pixel (u, v), bilinear, rounded to grey levels.
// Precondition: (u, v) at least h + 1 pixels inside the image.
void samplePatch(ImageView<const std::uint8_t> img, double u, double v, int h, std::uint8_t* out);

// Whether (u, v) lies at least m pixels inside the image (m + 1 on the far sides, for the
// bilinear neighbour).
bool insideWithMargin(ImageView<const std::uint8_t> img, double u, double v, int m);

// The template `tmpl` ((2h+1)^2, centred) searched in `img` over the integer positions within r
// px (a square) of (pu, pv), kept h + 2 px inside the image: the best ZNCC, when above
// min_zncc, refined to sub-pixel by Gauss-Newton on the translation (kept when it moves less
// than 1 px in each axis). Fills (u, v) (px) and returns true when found and at least h + 2 px
// inside the image; false for a flat template, a window outside the image or no score above
// min_zncc.
bool findPatch(ImageView<const std::uint8_t> img, const std::uint8_t* tmpl, int h, int pu, int pv,
               int r, float min_zncc, double& u, double& v);

}  // namespace svslam
