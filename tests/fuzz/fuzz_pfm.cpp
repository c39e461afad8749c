// PFM disparity files (readPfm: the loader of .pfm disparities and ground truth).
#include <cstdint>

#include "drivers/files/image_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  (void)svslam::drivers::parsePfm(data, size, "fuzz.pfm");
  return 0;
}
