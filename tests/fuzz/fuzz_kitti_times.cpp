// KITTI times.txt as the kitti: source reads it.
#include <cstdint>
#include <string>

#include "drivers/datasets/dataset_files.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  (void)svslam::drivers::parseKittiTimes(std::string(reinterpret_cast<const char*>(data), size),
                                         "times.txt");
  return 0;
}
