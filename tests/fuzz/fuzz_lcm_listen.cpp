// Any message as `svslam listen` receives it: the type picked by its hash, the validating
// decoder of that type (pose, stats, map_summary, map_tile, pose_correction, command,
// command_status, stereo_image) and the JSON line.
#include <cstdint>

#include "pipeline/cli/listen_lines.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  (void)svslam::cli::listenLine("FUZZ", data, size);
  return 0;
}
