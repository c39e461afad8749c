// svslam_lcm.stereo_image_t as the lcm: source receives it: decode, validate, calibration,
// copy into a frame.
#include <cstdint>

#include "drivers/lcm/lcm_messages.hpp"
#include "drivers/source/stereo_source.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace svslam::drivers;
  svslam_lcm::stereo_image_t m;
  if (!decodeLcm(data, size, m) || !validateStereoImage(m)) return 0;
  auto c = calibrationOf(m);
  if (!c) return 0;
  (void)checkStereoCalibration(*c);
  StereoFrame frame;
  (void)toStereoFrame(m, frame);
  return 0;
}
