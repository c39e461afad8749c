// KITTI calib.txt as the kitti: source reads it, then the source's calibration check.
#include <cstdint>
#include <string>

#include "drivers/datasets/dataset_files.hpp"
#include "drivers/source/stereo_source.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace svslam::drivers;
  auto c = parseKittiCalibration(std::string(reinterpret_cast<const char*>(data), size),
                                 "calib.txt");
  if (!c) return 0;
  c->width = 1241;
  c->height = 376;
  (void)checkStereoCalibration(*c);
  return 0;
}
