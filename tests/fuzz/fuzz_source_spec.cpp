// --source strings: split at the first ':' as openStereoSource does, then the parser of that
// kind (synthetic options, v4l2 setup, lcm spec), never opening anything (kitti: and euroc:
// take a folder, not a string to parse).
#include <cstdint>
#include <string>

#include "drivers/camera/v4l2_source.hpp"
#include "drivers/lcm/lcm_source.hpp"
#include "drivers/synthetic/synthetic_flight.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace svslam::drivers;
  const std::string spec(reinterpret_cast<const char*>(data), size);
  const auto colon = spec.find(':');
  const std::string kind = spec.substr(0, colon);
  const std::string arg = colon == std::string::npos ? "" : spec.substr(colon + 1);
  if (kind == "synthetic") (void)parseSyntheticOptions(arg);
  if (kind == "v4l2") (void)parseV4l2Setup(arg);
  if (kind == "lcm") (void)parseLcmSourceSpec(arg);
  return 0;
}
