// Dispatch of a source specification to its reader (see stereo_source.hpp).
#include "drivers/source/stereo_source.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "drivers/camera/libcamera_source.hpp"
#include "drivers/camera/v4l2_source.hpp"
#include "drivers/lcm/lcm_source.hpp"

namespace svslam::drivers {

Status checkStereoCalibration(const StereoCalibration& c) {
  if (Status s = c.validate(); !s) return s;
  auto bad = [](const char* what, double v, const char* limit) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "stereo calibration: %s = %g is out of range (%s)", what, v,
                  limit);
    return Status::invalidArgument(buf);
  };
  if (c.f_px > 1e6) return bad("f_px", c.f_px, "must be at most 1e6 px");
  if (std::abs(c.cx_px) > 1e6) return bad("cx_px", c.cx_px, "|cx| must be at most 1e6 px");
  if (std::abs(c.cy_px) > 1e6) return bad("cy_px", c.cy_px, "|cy| must be at most 1e6 px");
  if (c.baseline_m > 1e4) return bad("baseline_m", c.baseline_m, "must be at most 1e4 m");
  if (c.width > 65536 || c.height > 65536)
    return bad("image side", std::max(c.width, c.height), "must be at most 65536 px");
  return Status::ok();
}

Result<std::unique_ptr<StereoSource>> openStereoSource(const std::string& spec,
                                                       const StopQuery& stop) {
  const auto colon = spec.find(':');
  const std::string kind = spec.substr(0, colon);
  const std::string arg = colon == std::string::npos ? "" : spec.substr(colon + 1);
  if (kind == "kitti") return openKittiSource(arg);
  if (kind == "euroc") return openEurocSource(arg);
  if (kind == "lcm") return openLcmSource(arg, stop);
  if (kind == "v4l2") return openV4l2Source(arg, stop);
#ifdef SVSLAM_HAVE_LIBCAMERA
  if (kind == "libcamera") return openLibcameraSource(arg);
#else
  if (kind == "libcamera")
    return Status::failedPrecondition("libcamera support not built (libcamera-dev not found)");
#endif
#ifdef SVSLAM_HAVE_SYNTHETIC_SOURCE
  if (kind == "synthetic") return openSyntheticSource(arg);
#endif
  return Status::invalidArgument(
      "unknown source '" + spec +
      "' (use kitti:DIR, euroc:DIR, synthetic[:key=value,...], v4l2:/dev/videoA[,/dev/videoB], "
      "libcamera:ID_LEFT,ID_RIGHT or lcm:CHANNEL)");
}

}  // namespace svslam::drivers
