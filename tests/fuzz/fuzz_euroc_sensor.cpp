// EuRoC mav0/camN/sensor.yaml as the euroc: source reads it (intrinsics, distortion,
// resolution, T_BS).
#include <cstdint>
#include <string>

#include "drivers/datasets/dataset_files.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  (void)svslam::drivers::parseEurocSensor(std::string(reinterpret_cast<const char*>(data), size),
                                          "sensor.yaml");
  return 0;
}
