// svslam_lcm.pose_t as received: the validating decoder, the conversion to a PoseReport, and
// back to the wire (a pose accepted from the wire must be publishable again).
#include <cstdint>
#include <cstdio>
#include <cstdlib>

#include "drivers/lcm/lcm_messages.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace svslam::drivers;
  svslam_lcm::pose_t m;
  if (!decodeLcm(data, size, m)) return 0;
  auto r = fromLcm(m);
  if (!r) return 0;
  if (auto back = toLcm(*r); !back) {
    std::fprintf(stderr, "accepted pose not publishable: %s\n", back.status().message().c_str());
    std::abort();
  }
  return 0;
}
