// EuRoC mav0/camN/data.csv as the euroc: source reads it.
#include <cstdint>
#include <string>

#include "drivers/datasets/dataset_files.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  (void)svslam::drivers::parseEurocDataCsv(std::string(reinterpret_cast<const char*>(data), size),
                                           "data.csv");
  return 0;
}
