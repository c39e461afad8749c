#pragma once
// An altimeter's reading on the wire (svslam_lcm.altitude_t, lcm/altitude_t.lcm): the scale
// source of the monocular mode (slam.mono_scale = altitude).
#include <cstddef>
#include <cstdint>

#include "core/status.hpp"
#include "core/time.hpp"
#include "svslam_lcm/altitude_t.hpp"

namespace svslam::drivers {

struct AltitudeReading {
  TimeNs t_ns = 0;          // measurement time, the frames' clock
  double altitude_m = 0;    // camera height above the ground, m, finite, > 0
  double sigma_m = 0;       // its standard deviation, m, finite, >= 0
};

// Reading -> wire; invalidArgument naming the field when a value is out of range.
Result<svslam_lcm::altitude_t> toLcm(const AltitudeReading& r);
// Untrusted bytes -> reading: kCorruptData for bytes that are not an altitude_t (hash, size),
// invalidArgument naming the field for a value out of range (NaN, <= 0 altitude, negative
// sigma, a utime that overflows nanoseconds). `out` is untouched on error.
Status decodeAltitude(const std::uint8_t* data, std::size_t size, AltitudeReading& out);

}  // namespace svslam::drivers
