#pragma once
// Left/right image pairs of a calibration set on disk (svslam calibrate).
//
// One folder (listCalibrationPairs(dir)): the images whose names start with "left" pair with
// those starting with "right" by the rest of the name (case-sensitive, extension included):
// left01.jpg + right01.jpg, left_a.png + right_a.png. Other files are ignored.
// Two folders (listCalibrationPairs(left_dir, right_dir)): images of identical file name.
// Images: .png .jpg .jpeg .pgm .ppm .bmp .tif .tiff (extension case-insensitive). Pairs are
// sorted by name. Errors name the problem: a missing folder, no image pair, an image without
// its partner ("unequal left/right: 13 left and 12 right images; right05.jpg has no left").
#include <string>
#include <vector>

#include "core/status.hpp"

namespace svslam::drivers {

struct CalibrationPairPaths {
  std::string name;  // the common part: "01.jpg" (one folder) or the file name (two folders)
  std::string left, right;
};

Result<std::vector<CalibrationPairPaths>> listCalibrationPairs(const std::string& dir);
Result<std::vector<CalibrationPairPaths>> listCalibrationPairs(const std::string& left_dir,
                                                               const std::string& right_dir);

}  // namespace svslam::drivers
