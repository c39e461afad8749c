#pragma once
// Helpers of the tests that read ../shared/data: locate a case, run DenseStereo, score it.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "eval/disparity_metrics.hpp"
#include "pipeline/tools/stereo_case.hpp"

namespace svslam::testing {

inline std::string dataDir() { return SVSLAM_DATA_DIR; }

inline bool dataPresent(const std::string& sub) {
  return std::filesystem::exists(dataDir() + "/" + sub);
}

struct CaseRun {
  cli::LoadedCase loaded;
  DisparityResult result;
  DisparityMetrics metrics;
};

// Loads the case in folder `sub` of the data dir (non-occluded mask, derived from the ground
// truth when the data set ships none), runs DenseStereo with `params` (max_disp from the case)
// and scores it. Fails the test on any error.
inline CaseRun runCase(const std::string& sub, DenseStereoParams params) {
  CaseRun run;
  auto info = drivers::findStereoGtCase(dataDir() + "/" + sub, "nonocc", "");
  EXPECT_TRUE(info.isOk()) << info.status().message();
  if (!info) return run;
  auto loaded = cli::loadCase(*info, true, true);
  EXPECT_TRUE(loaded.isOk()) << loaded.status().message();
  if (!loaded) return run;
  run.loaded = std::move(loaded).value();
  params.max_disp = run.loaded.info.max_disp;
  SerialExecutor ex;
  Status s = cli::computeDisparity(run.loaded, params, ex, run.result, nullptr);
  EXPECT_TRUE(s.isOk()) << s.message();
  auto m = evaluateDisparity(run.result.disparity_px.cview(), run.loaded.gt.cview(),
                             run.loaded.mask.cview());
  EXPECT_TRUE(m.isOk()) << m.status().message();
  if (m) run.metrics = *m;
  return run;
}

}  // namespace svslam::testing
