// svslam_lcm.command_t as the command listener receives it: decode, convert, then the token
// gate.
#include <cstdint>

#include "drivers/lcm/command_gate.hpp"
#include "drivers/lcm/lcm_messages.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace svslam::drivers;
  svslam_lcm::command_t m;
  if (!decodeLcm(data, size, m)) return 0;
  auto c = fromLcm(m);
  if (!c) return 0;
  CommandGate gate(true, "fuzz-token", 10.0);
  (void)gate.admit(c->token, c->t_ns);
  return 0;
}
