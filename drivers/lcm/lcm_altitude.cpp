#include "drivers/lcm/lcm_altitude.hpp"

#include <cmath>
#include <string>

#include "drivers/lcm/lcm_messages.hpp"

namespace svslam::drivers {
namespace {

Status checkValues(double altitude_m, double sigma_m) {
  if (!std::isfinite(altitude_m) || !(altitude_m > 0.0))
    return Status::invalidArgument("altitude_t: altitude_m must be finite and > 0 (got " +
                                   std::to_string(altitude_m) + ")");
  if (!std::isfinite(sigma_m) || !(sigma_m >= 0.0))
    return Status::invalidArgument("altitude_t: sigma_m must be finite and >= 0 (got " +
                                   std::to_string(sigma_m) + ")");
  return Status::ok();
}

}  // namespace

Result<svslam_lcm::altitude_t> toLcm(const AltitudeReading& r) {
  if (Status s = checkValues(r.altitude_m, r.sigma_m); !s) return s;
  svslam_lcm::altitude_t m;
  m.utime = toUtime(r.t_ns);
  m.altitude_m = r.altitude_m;
  m.sigma_m = r.sigma_m;
  return m;
}

Status decodeAltitude(const std::uint8_t* data, std::size_t size, AltitudeReading& out) {
  svslam_lcm::altitude_t m;
  if (Status s = decodeLcm(data, size, m); !s) return s;
  auto t = fromUtime(m.utime);
  if (!t) return Status::invalidArgument("altitude_t: " + t.status().message());
  if (Status s = checkValues(m.altitude_m, m.sigma_m); !s) return s;
  out = AltitudeReading{*t, m.altitude_m, m.sigma_m};
  return Status::ok();
}

}  // namespace svslam::drivers
