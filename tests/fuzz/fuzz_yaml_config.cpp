// The YAML configuration of `svslam run --config` (every key read and checked, as the service
// loads it).
#include <cstdint>
#include <string>

#include "pipeline/config/run_config.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  svslam::config::RunConfig cfg;
  (void)svslam::config::parseRunConfig(std::string(reinterpret_cast<const char*>(data), size),
                                       "fuzz.yaml", cfg);
  return 0;
}
