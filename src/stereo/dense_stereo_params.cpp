// Names and validation of DenseStereoParams.
#include <cmath>
#include <initializer_list>
#include <string>

#include "stereo/dense_stereo.hpp"

namespace svslam {

const char* toString(MatchingCost c) { return c == MatchingCost::kCensus ? "census" : "sad"; }

const char* toString(SadPrefilter p) {
  switch (p) {
    case SadPrefilter::kNone:
      return "none";
    case SadPrefilter::kMeanRemoval:
      return "mean";
    case SadPrefilter::kXSobel:
      return "xsobel";
  }
  return "unknown";
}

bool parseMatchingCost(const std::string& s, MatchingCost& out) {
  if (s == "census") {
    out = MatchingCost::kCensus;
    return true;
  }
  if (s == "sad") {
    out = MatchingCost::kSad;
    return true;
  }
  return false;
}

bool parseSadPrefilter(const std::string& s, SadPrefilter& out) {
  for (SadPrefilter p : {SadPrefilter::kNone, SadPrefilter::kMeanRemoval, SadPrefilter::kXSobel}) {
    if (s == toString(p)) {
      out = p;
      return true;
    }
  }
  return false;
}

int DenseStereoParams::maxPixelCost() const {
  if (cost == MatchingCost::kCensus) return census_w * census_h - 1;
  return prefilter == SadPrefilter::kNone ? 255 : 2 * prefilter_cap;
}

Status DenseStereoParams::validate() const {
  auto bad = [](const std::string& m) { return Status::invalidArgument(m); };
  auto odd = [](int v) { return v > 0 && v % 2 == 1; };
  if (cost == MatchingCost::kCensus) {
    if (!odd(census_w) || !odd(census_h) || census_w < 3 || census_h < 3)
      return bad("census window " + std::to_string(census_w) + "x" + std::to_string(census_h) +
                 ": each side must be odd and at least 3");
    if (census_w * census_h - 1 > 64)
      return bad("census window " + std::to_string(census_w) + "x" + std::to_string(census_h) +
                 " has more than 64 neighbours (use at most 9x7 or 7x9)");
  } else {
    if (prefilter_cap < 1 || prefilter_cap > 63) return bad("prefilter_cap must be in 1..63");
    if (prefilter == SadPrefilter::kMeanRemoval &&
        (!odd(prefilter_size) || prefilter_size < 3 || prefilter_size > 21))
      return bad("prefilter_size must be odd in 3..21");
  }
  if (!odd(window_w) || !odd(window_h) || window_w > 31 || window_h > 31)
    return bad("aggregation window sides must be odd in 1..31");
  if (static_cast<long>(window_w) * window_h * maxPixelCost() > 0xFFFE)
    return bad("aggregation window too large for 16-bit costs: window_w * window_h * " +
               std::to_string(maxPixelCost()) + " must be <= 65534");
  if (min_disp < 0) return bad("min_disp must be >= 0");
  if (max_disp <= min_disp) return bad("max_disp must be > min_disp");
  if (max_disp - min_disp > 1024) return bad("max_disp - min_disp must be <= 1024");
  if (uniqueness_pct < 0 || uniqueness_pct > 100) return bad("uniqueness_pct must be in 0..100");
  if (!std::isfinite(texture_threshold) || texture_threshold < 0.0f)
    return bad("texture_threshold must be finite and >= 0");
  if (lr_max_diff < 0) return bad("lr_max_diff must be >= 0");
  if (num_stripes < 1 || num_stripes > 256) return bad("num_stripes must be in 1..256");
  if (!simd::backendAvailable(backend))
    return bad(std::string("SIMD backend '") + simd::backendName(backend) +
               "' is not available on this CPU or build");
  if (Status s = sigma_model.validate(); !s) return s;
  return Status::ok();
}

}  // namespace svslam
