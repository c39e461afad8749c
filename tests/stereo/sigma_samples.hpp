#pragma once
// Curvature / error samples of a ground-truth scene and the leave-one-scene-out honesty check
// shared by the dense (tests/stereo) and sparse (tests/features) sigma calibration tests.
#include <gtest/gtest.h>

#include <cstddef>
#include <string>
#include <vector>

#include "real_data.hpp"
#include "stereo/sigma_model.hpp"

namespace svslam::testing {

// The ground-truth scenes both calibrations are checked on (non-occluded masks).
inline const std::vector<std::string> kSigmaScenes = {
    "middlebury_v2/tsukuba", "middlebury_v2/venus", "middlebury_v2/teddy", "middlebury_v2/cones",
    "middlebury2006_aloe"};

// The first of kSigmaScenes absent from the shared data (as dataDir()/scene), "" if none is.
inline std::string missingSigmaScene() {
  for (const auto& c : kSigmaScenes)
    if (!dataPresent(c)) return dataDir() + "/" + c;
  return "";
}

struct SigmaSamples {
  std::vector<float> kappa;  // peak curvature of each sample
  std::vector<float> err;    // |d - d_true|, px
};

// All scenes' samples pooled, except scene `skip` (-1: none).
inline SigmaSamples pooledSamples(const std::vector<SigmaSamples>& scenes, int skip = -1) {
  SigmaSamples all;
  for (std::size_t t = 0; t < scenes.size(); ++t) {
    if (static_cast<int>(t) == skip) continue;
    all.kappa.insert(all.kappa.end(), scenes[t].kappa.begin(), scenes[t].kappa.end());
    all.err.insert(all.err.end(), scenes[t].err.begin(), scenes[t].err.end());
  }
  return all;
}

// For each scene h: fit a model with `bins` bins on the other scenes, and the share of scene h's
// errors inside one sigma of it. Empty when a fit fails (reported as a test failure).
inline std::vector<double> heldOutCoverages(const std::vector<SigmaSamples>& scenes, int bins) {
  std::vector<double> cov;
  for (std::size_t h = 0; h < scenes.size(); ++h) {
    const SigmaSamples train = pooledSamples(scenes, static_cast<int>(h));
    auto model = fitSigmaModel(train.kappa, train.err, bins);
    EXPECT_TRUE(model.isOk()) << model.status().message();
    if (!model) return {};
    cov.push_back(sigmaCoverage(*model, scenes[h].kappa, scenes[h].err));
  }
  return cov;
}

}  // namespace svslam::testing
