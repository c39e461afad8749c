#pragma once
// Writing a DisparityResult to the files a user asked for, shared by the CLI commands.
#include <string>

#include "core/status.hpp"
#include "stereo/dense_stereo.hpp"

namespace svslam::cli {

// Checks before any computation that an output path has a supported extension (`what` names the
// option): disparity .pfm/.png, sigma .pfm, color .png.
Status checkOutputPath(const std::string& path, const std::string& what);

// Writes the non-empty paths: disparity (.pfm float or .png KITTI uint16), sigma_d (.pfm) and a
// colour picture (.png) scaled to max_disp.
Status writeDisparityOutputs(const DisparityResult& r, const std::string& disparity_path,
                             const std::string& sigma_path, const std::string& color_path,
                             int max_disp);

}  // namespace svslam::cli
