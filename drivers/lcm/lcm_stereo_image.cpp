// The stereo_image_t wire type (another process feeding images): checks of a received message,
// its calibration and frame, and the message made from a pair (lcm_messages.hpp).
#include <climits>
#include <cmath>
#include <cstring>
#include <limits>

#include "drivers/lcm/lcm_messages.hpp"

namespace svslam::drivers {
namespace {

constexpr int kMaxImageSide = 16384;  // px, per side: larger claims are malformed messages

bool finite(double v) { return std::isfinite(v); }

}  // namespace

Status validateStereoImage(const svslam_lcm::stereo_image_t& m) {
  const std::string what = "stereo_image_t seq " + std::to_string(m.seq);
  if (m.width < 1 || m.height < 1 || m.width > kMaxImageSide || m.height > kMaxImageSide)
    return Status::invalidArgument(what + ": size " + std::to_string(m.width) + "x" +
                                   std::to_string(m.height) + " outside [1, 16384]");
  if (m.stride < m.width)
    return Status::invalidArgument(what + ": stride " + std::to_string(m.stride) +
                                   " < width " + std::to_string(m.width));
  const std::int64_t expect = std::int64_t{m.stride} * m.height;
  if (m.left_size != expect || m.right_size != expect ||
      m.left.size() != static_cast<std::size_t>(expect) ||
      m.right.size() != static_cast<std::size_t>(expect))
    return Status::invalidArgument(what + ": left_size " + std::to_string(m.left_size) +
                                   " / right_size " + std::to_string(m.right_size) +
                                   " != stride * height = " + std::to_string(expect));
  if (!finite(m.f_px) || m.f_px <= 0.0)
    return Status::invalidArgument(what + ": f_px must be finite and > 0");
  if (!finite(m.baseline_m) || m.baseline_m <= 0.0)
    return Status::invalidArgument(what + ": baseline_m must be finite and > 0");
  if (!finite(m.cx_px) || !finite(m.cy_px) || m.cx_px < 0.0 || m.cx_px >= m.width ||
      m.cy_px < 0.0 || m.cy_px >= m.height)
    return Status::invalidArgument(what + ": principal point outside the image");
  if (auto t = fromUtime(m.utime); !t) return t.status();
  return Status::ok();
}

Result<StereoCalibration> calibrationOf(const svslam_lcm::stereo_image_t& m) {
  if (Status s = validateStereoImage(m); !s) return s;
  StereoCalibration c;
  c.f_px = m.f_px;
  c.cx_px = m.cx_px;
  c.cy_px = m.cy_px;
  c.baseline_m = m.baseline_m;
  c.width = m.width;
  c.height = m.height;
  return c;
}

Status toStereoFrame(const svslam_lcm::stereo_image_t& m, StereoFrame& out) {
  if (Status s = validateStereoImage(m); !s) return s;
  out.t_ns = m.utime * kNsPerUs;
  out.left.resize(m.width, m.height);
  out.right.resize(m.width, m.height);
  const auto stride = static_cast<std::size_t>(m.stride);
  for (int y = 0; y < m.height; ++y) {
    std::memcpy(out.left.row(y), m.left.data() + stride * std::size_t(y), std::size_t(m.width));
    std::memcpy(out.right.row(y), m.right.data() + stride * std::size_t(y), std::size_t(m.width));
  }
  return Status::ok();
}

Result<svslam_lcm::stereo_image_t> toLcmStereoImage(const ImageU8& left, const ImageU8& right,
                                                    const StereoCalibration& calib, TimeNs t_ns,
                                                    std::int64_t seq) {
  if (Status s = calib.validate(); !s) return s;
  if (left.width() != calib.width || left.height() != calib.height ||
      right.width() != calib.width || right.height() != calib.height)
    return Status::invalidArgument("stereo image: left/right size differs from the calibration");
  svslam_lcm::stereo_image_t m;
  m.utime = toUtime(t_ns);
  m.seq = seq;
  m.width = m.stride = calib.width;
  m.height = calib.height;
  m.f_px = calib.f_px;
  m.cx_px = calib.cx_px;
  m.cy_px = calib.cy_px;
  m.baseline_m = calib.baseline_m;
  const auto w = static_cast<std::size_t>(calib.width);
  m.left_size = m.right_size = calib.width * calib.height;
  m.left.resize(static_cast<std::size_t>(m.left_size));
  m.right.resize(static_cast<std::size_t>(m.right_size));
  for (int y = 0; y < calib.height; ++y) {
    std::memcpy(m.left.data() + w * std::size_t(y), left.row(y), w);
    std::memcpy(m.right.data() + w * std::size_t(y), right.row(y), w);
  }
  if (Status s = validateStereoImage(m); !s) return s;
  return m;
}

}  // namespace svslam::drivers
