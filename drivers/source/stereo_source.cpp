// Dispatch of a source specification to its reader (see stereo_source.hpp).
#include "drivers/source/stereo_source.hpp"

#include "drivers/lcm/lcm_source.hpp"
#include "drivers/camera/libcamera_source.hpp"
#include "drivers/camera/v4l2_source.hpp"

namespace svslam::drivers {

Result<std::unique_ptr<StereoSource>> openStereoSource(const std::string& spec) {
  const auto colon = spec.find(':');
  const std::string kind = spec.substr(0, colon);
  const std::string arg = colon == std::string::npos ? "" : spec.substr(colon + 1);
  if (kind == "kitti") return openKittiSource(arg);
  if (kind == "euroc") return openEurocSource(arg);
  if (kind == "lcm") return openLcmSource(arg);
  if (kind == "v4l2") return openV4l2Source(arg);
#ifdef SVSLAM_HAVE_LIBCAMERA
  if (kind == "libcamera") return openLibcameraSource(arg);
#else
  if (kind == "libcamera")
    return Status::failedPrecondition("libcamera support not built (libcamera-dev not found)");
#endif
#ifdef SVSLAM_HAVE_SYNTHETIC_SOURCE
  if (kind == "synthetic") return openSyntheticSource(arg);
#endif
  return Status::invalidArgument("unknown source '" + spec +
                                 "' (use kitti:DIR, euroc:DIR or synthetic[:key=value,...])");
}

}  // namespace svslam::drivers
