// Trajectory files (KITTI or TUM, as eval-trajectory, eval-dem, plot and the loop stage read
// them), then the pairing of a trajectory with itself that eval-trajectory does.
#include <cstdint>
#include <string>
#include <vector>

#include "drivers/files/trajectory_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace svslam::drivers;
  auto t = parseTrajectory(std::string(reinterpret_cast<const char*>(data), size), "fuzz.txt");
  if (!t) return 0;
  std::vector<Eigen::Isometry3d> gt, est;
  (void)associateTrajectories(*t, *t, 0.01, gt, est);
  return 0;
}
