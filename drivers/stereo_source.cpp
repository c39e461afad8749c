// Dispatch of a source specification to its reader (see stereo_source.hpp).
#include "drivers/stereo_source.hpp"

#include "drivers/lcm_source.hpp"

namespace svslam::io {

Result<std::unique_ptr<StereoSource>> openStereoSource(const std::string& spec) {
  const auto colon = spec.find(':');
  const std::string kind = spec.substr(0, colon);
  const std::string arg = colon == std::string::npos ? "" : spec.substr(colon + 1);
  if (kind == "kitti") return openKittiSource(arg);
  if (kind == "euroc") return openEurocSource(arg);
  if (kind == "lcm") return openLcmSource(arg);
#ifdef SVSLAM_HAVE_SYNTHETIC_SOURCE
  if (kind == "synthetic") return openSyntheticSource(arg);
#endif
  return Status::invalidArgument("unknown source '" + spec +
                                 "' (use kitti:DIR, euroc:DIR or synthetic[:key=value,...])");
}

}  // namespace svslam::io
