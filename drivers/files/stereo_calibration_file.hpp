#pragma once
// The stereo calibration file of the `v4l2:` and `libcamera:` sources (docs/cameras.md), read and
// written here and nowhere else.
//
// An OpenCV FileStorage file (YAML, XML or JSON, chosen by the extension) for the RAW cameras:
//   K1, K2   3x3 camera matrices of the left / right camera, px
//   D1, D2   distortion, OpenCV order k1 k2 p1 p2 [k3 ...]; may be empty (read as 5 zeros)
//   R, T     p_right = R p_left + T; T in metres (right camera at +x: T ~ [-baseline, 0, 0])
//   image_width, image_height   size of one view, px
// Matrices are read as CV_64F (any stored depth); NaN/inf, a wrong element count, focal lengths
// <= 0 or a missing key are corruptData errors naming the key and the file.
#include <opencv2/core.hpp>
#include <string>

#include "core/status.hpp"

namespace svslam::drivers {

struct StereoCalibrationFile {
  cv::Mat K1, D1, K2, D2;     // K: 3x3 CV_64F, px; D: 1xN CV_64F (N >= 4)
  cv::Mat R, T;               // R: 3x3, T: 3x1 CV_64F (metres), p_right = R p_left + T
  int width = 0, height = 0;  // one view, px
};

Result<StereoCalibrationFile> readStereoCalibrationFile(const std::string& file);

// Writes `c` to `file` (format by extension: .yaml/.yml, .xml, .json) through a temporary file
// in the same folder (".tmp-<name>") renamed over `file`, so `file` is either absent, the old
// file or the complete new one. ioError naming the file on failure; no temporary is left.
Status writeStereoCalibrationFile(const std::string& file, const StereoCalibrationFile& c);

}  // namespace svslam::drivers
