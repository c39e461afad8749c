#pragma once
// A rendered stereo flight over a textured heightfield with exact ground truth: the
// `synthetic[:key=value,...]` stereo source (stereo_source.hpp), svslam's built-in default.
//
// World frame W: x east, y north, z up, metres; the ground is the surface z = heightAt(x, y), a
// seeded sum of four octaves of smooth value noise (synthetic_terrain.hpp), |height| <= relief_m.
// Its albedo is seeded multi-octave noise plus patches and rectangles at every scale from metres
// to millimetres, band-limited by the pixel footprint (no aliasing, nothing repeats), and shaded
// by a fixed sun (Lambert: view-independent, so both cameras see the same radiance).
//
// Cameras: rectified pinhole pair, camera frame x right, y down, z forward (core/camera.hpp).
// The right camera sits at +baseline_m along the left camera's x axis; same f, cx = (W-1)/2,
// cy = (H-1)/2, f = (W/2) / tan(hfov/2). Body frame B: x forward (along the path), y left, z up;
// R_W_B = Rz(yaw) Ry(pitch) Rx(roll) with yaw the path heading and roll, pitch a sinusoidal
// wobble. The camera is pitched down by camera_pitch_deg about the body y axis: 90 deg looks
// straight down (blimp: image x = body right, image y = body backward, image top = forward),
// a small angle looks forward (rover: image y = down, sky above the horizon).
//
// Path: a closed ellipse with semi-axes a, b = loop_aspect * a, a chosen so its perimeter is
// loop_length_m, travelled once over the sequence at constant angular rate
// theta_i = 2 pi i / frames (frame `frames` would coincide with frame 0). The ellipse centre is
// the world origin, frame 0 at (a, 0). Blimp altitude above the datum z = 0:
//   z = (min + max) / 2 + (max - min) / 2 sin(theta), within [altitude_min_m, altitude_max_m].
// Rover: the left camera is camera_height_m above the ground below it.
// Time: t_ns = i * round(1e9 / rate_hz).
//
// Rendering: every pixel is a ray o + t d with d = R_W_C ((u - cx)/f, (v - cy)/f, 1), so t is the
// camera depth z. The first t with g(t) = o_z + t d_z - h(o_xy + t d_xy) = 0 is found inside the
// slab |z| <= relief_m: when g is provably monotone (d_z + L |d_xy| < 0, L the terrain slope
// bound; always so for the blimp) by safeguarded Newton from the depth extrapolated from the two
// previous pixels of the row; else by marching with steps max(g / (|d_z| + L |d_xy|), 1.5 % of t)
// (the first is Lipschitz-safe, the second only skips bumps thinner than 1.5 % of the range)
// until g changes sign, then safeguarded Newton in that bracket. A Newton step delta is final
// once the bound K |d_xy|^2 delta^2 / (2 |g'|) on the remaining error (K the terrain curvature
// bound) is below 1e-7 m: depths exact to 1e-7 m, disparities to ~1e-6 px. Usually one height
// evaluation per pixel. Rays that miss within max_range_m see the sky (a
// smooth gradient); terrain fades into the horizon sky colour with distance (haze_m). Pixel
// noise: near-Gaussian (Irwin-Hall sum of 4 uniforms), seeded per (seed, frame, camera, pixel),
// independent of the stripes.
#include <Eigen/Geometry>
#include <cstdint>
#include <string>

#include "core/camera.hpp"
#include "core/executor.hpp"
#include "core/image.hpp"
#include "core/status.hpp"
#include "core/time.hpp"
#include "drivers/synthetic/synthetic_terrain.hpp"

namespace svslam::drivers {

enum class FlightVariant { kBlimp, kRover };
const char* toString(FlightVariant v);
bool parseFlightVariant(const std::string& s, FlightVariant& out);

// Option keys of "synthetic:key=value,..." are the field names. In-class defaults are the blimp's;
// forVariant() gives each variant's defaults.
struct SyntheticFlightParams {
  FlightVariant variant = FlightVariant::kBlimp;
  int frames = 100;                // sequence length, 1..100000
  int loop_frames = 0;             // frames per loop (the flight repeats it), 0 = frames
  // A failed right camera (camera-loss tests): the right images of frames [right_black_from,
  // right_black_to) are black; right_black_from = -1: none; right_black_to = -1: to the end.
  int right_black_from = -1;
  int right_black_to = -1;
  // Both cameras lost (a real loss of tracking: lens covered, camera restarted): the left and
  // right images of frames [black_from, black_to) are black; black_from = -1: none;
  // black_to = -1: to the end.
  int black_from = -1;
  int black_to = -1;
  int width = 1024;                // px, 32..8192
  int height = 768;                // px, 32..8192
  double baseline_m = 2.2;         // m, (0, 100]; rover 0.5
  double hfov_deg = 60.0;          // horizontal field of view, deg, [10, 150]
  double rate_hz = 10.0;           // frame rate, Hz, (0, 10000]
  double altitude_min_m = 25.0;    // blimp, above z = 0, m, [20, 35] and > relief_m + 5
  double altitude_max_m = 30.0;    // blimp, m, [altitude_min_m, 35]
  double camera_height_m = 1.2;    // rover, above the ground, m, [0.2, 20]
  double camera_pitch_deg = 90.0;  // down tilt from horizontal, deg, [0, 90]; rover 8
  double loop_length_m = 70.0;     // horizontal length of the closed loop, m, [1, 2000]; rover 30
  double loop_aspect = 0.6;        // minor / major semi-axis of the loop ellipse, [0.1, 1]
  double wobble_deg = 3.0;         // roll and pitch wobble amplitude, deg, [0, 20]; rover 1
  double wobble_period_s = 4.0;    // roll wobble period, s, [0.001, 1e6]; pitch: 1.37 times it
  double relief_m = 3.0;           // terrain |height| bound, m, [0, 1000]; rover 0.8
  double terrain_cell_m = 48.0;    // largest terrain wavelength, m, [1, 10000]; rover 40
  double noise_sigma = 1.0;        // pixel noise standard deviation, grey levels, [0, 50]
  double max_range_m = 1000.0;     // ground farther than this is sky, m, [1, 1e6]
  // > 0: the albedo repeats every texture_period_m along x and y (the heights do not): distinct
  // places that look alike, to test loop closing against false loops. m, 0 or [5, 1e4].
  double texture_period_m = 0.0;
  double haze_m = 400.0;   // terrain contrast scales by exp(-distance / haze_m), m, [1, 1e9]
  int supersample = 1;     // s x s rays per pixel (1 = band-limited point sample), 1..4
  std::uint64_t seed = 1;  // terrain, texture, wobble phases and noise

  static SyntheticFlightParams forVariant(FlightVariant v);
  // Ok, or an invalidArgument naming the offending field.
  Status validate() const;
};

class SyntheticFlight {
 public:
  // Precondition: params.validate() is ok (use create()).
  explicit SyntheticFlight(const SyntheticFlightParams& params);
  static Result<SyntheticFlight> create(const SyntheticFlightParams& params);

  const SyntheticFlightParams& params() const { return params_; }
  const StereoCalibration& calibration() const { return calib_; }
  int size() const { return params_.frames; }
  TimeNs timeNs(int index) const { return static_cast<TimeNs>(index) * period_ns_; }

  // Pose of the LEFT camera at frame `index` (any integer; the path is periodic): maps camera
  // coordinates to world coordinates.
  Eigen::Isometry3d pose(int index) const;
  Eigen::Isometry3d rightPose(int index) const;  // pose(index) * translation(baseline_m, 0, 0)

  // Ground height z at world (x, y), metres.
  double heightAt(double x, double y) const { return terrain_.height(x, y); }
  // Same, with the slope dz/dx, dz/dy.
  double heightAt(double x, double y, double& dz_dx, double& dz_dy) const {
    return terrain_.height(x, y, dz_dx, dz_dy);
  }
  double maxAbsHeight() const { return terrain_.maxAbsHeight(); }

  // Renders the pair of frame `index` (0 <= index < size()); images resized to width x height.
  // When depth_left is given it receives the exact depth z (metres) of every left pixel centre,
  // +inf on the sky. Rows run as stripes through `executor`; the bytes do not depend on it.
  Status render(int index, ImageU8& left, ImageU8& right, ImageF32* depth_left = nullptr) const;
  Status render(int index, ImageU8& left, ImageU8& right, ImageF32* depth_left,
                Executor& executor) const;
  // Exact depth z of every left pixel centre (metres, +inf on the sky), no shading.
  Status renderDepth(int index, ImageF32& depth_left) const;
  // Ground-truth disparity f b / z of the left view (0 on the sky).
  Status trueDisparity(int index, ImageF32& disparity_px) const;

  // First intersection t > 0 of the world ray o + t d with the ground, within max_range_m;
  // false on the sky. A positive `t_guess` seeds Newton when the ray is provably monotone.
  // Optionally returns the ground slope at the hit.
  bool intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_guess, double& t,
                 double* dz_dx = nullptr, double* dz_dy = nullptr) const;

 private:
  struct View;
  // Depths of the last two rays along a row; the guess for the next one extrapolates them.
  struct RayHistory {
    double t1 = -1.0, t2 = -1.0;
    double guess() const { return t2 > 0.0 && t1 > 0.0 ? 2.0 * t1 - t2 : t1; }
    void push(double t) {
      t2 = t1;
      t1 = t;
    }
  };
  void renderRows(const View& view, int y0, int y1, ImageU8* image, ImageF32* depth) const;
  double shadeRay(const Eigen::Vector3d& o, const Eigen::Vector3d& d, RayHistory& history) const;

  SyntheticFlightParams params_;
  StereoCalibration calib_;
  TimeNs period_ns_ = 0;
  double semi_a_m_ = 0.0, semi_b_m_ = 0.0;  // loop ellipse
  double roll_phase_ = 0.0, pitch_phase_ = 0.0;
  synth::Terrain terrain_;
  synth::Albedo albedo_;
  Eigen::Vector3d sun_W_;  // unit vector towards the sun
};

class StereoSource;

// Parses "" or "key=value,key=value,..." (keys: the SyntheticFlightParams field names; `variant`
// = blimp | rover selects the defaults, wherever it appears). Errors name the key.
Result<SyntheticFlightParams> parseSyntheticOptions(const std::string& options);

// The scene behind a source opened by openSyntheticSource, or nullptr for any other source
// (e.g. to query heightAt for an elevation map). Valid while the source lives.
const SyntheticFlight* asSyntheticFlight(const StereoSource& source);

}  // namespace svslam::drivers
