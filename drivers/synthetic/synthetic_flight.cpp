#include "drivers/synthetic/synthetic_flight.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace svslam::drivers {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;
constexpr double kDepthTol_m = 1e-7;  // bound on the depth error of the accepted root, m

// Perimeter of the ellipse with semi-axes 1 and k: integral of sqrt(sin^2 + k^2 cos^2) over a
// period; the midpoint rule is spectrally accurate for a smooth periodic integrand.
double unitEllipsePerimeter(double k) {
  constexpr int kN = 4096;
  double sum = 0.0;
  for (int i = 0; i < kN; ++i) {
    const double th = 2.0 * kPi * (i + 0.5) / kN;
    sum += std::hypot(std::sin(th), k * std::cos(th));
  }
  return sum * 2.0 * kPi / kN;
}

Status outOfRange(const char* field, const std::string& range) {
  return Status::invalidArgument(std::string("synthetic flight: ") + field + " must be " + range);
}

bool inRange(double v, double lo, double hi) { return std::isfinite(v) && v >= lo && v <= hi; }

// Sky grey level by ray elevation sin(e) = d_z / |d|: brightest at the horizon.
double skyAt(double sin_elev) { return 215.0 - 70.0 * std::sqrt(std::max(sin_elev, 0.0)); }

// Zero-mean, unit-variance, near-Gaussian noise from a 64-bit hash: the Irwin-Hall sum of four
// 16-bit uniforms (variance 4/12), scaled by sqrt(3); bounded by +-3.46 (no libm calls).
double gaussianFromHash(std::uint64_t h) {
  const double sum =
      static_cast<double>((h & 0xFFFF) + ((h >> 16) & 0xFFFF) + ((h >> 32) & 0xFFFF) + (h >> 48)) +
      2.0;  // centres of the 16-bit bins
  return (sum * (1.0 / 65536.0) - 2.0) * 1.7320508075688772;
}

}  // namespace

const char* toString(FlightVariant v) { return v == FlightVariant::kRover ? "rover" : "blimp"; }

bool parseFlightVariant(const std::string& s, FlightVariant& out) {
  if (s == "blimp") {
    out = FlightVariant::kBlimp;
  } else if (s == "rover") {
    out = FlightVariant::kRover;
  } else {
    return false;
  }
  return true;
}

SyntheticFlightParams SyntheticFlightParams::forVariant(FlightVariant v) {
  SyntheticFlightParams p;
  p.variant = v;
  if (v == FlightVariant::kRover) {
    p.baseline_m = 0.5;
    p.camera_pitch_deg = 8.0;
    p.loop_length_m = 30.0;
    p.wobble_deg = 1.0;
    p.relief_m = 0.8;
    p.terrain_cell_m = 40.0;
  }
  return p;
}

Status SyntheticFlightParams::validate() const {
  if (frames < 1 || frames > 100000) return outOfRange("frames", "in 1..100000");
  if (loop_frames < 0 || loop_frames > 100000) return outOfRange("loop_frames", "in 0..100000");
  if (right_black_from < -1 || right_black_from > 100000)
    return outOfRange("right_black_from", "in -1..100000");
  if (right_black_to < -1 || right_black_to > 100000)
    return outOfRange("right_black_to", "in -1..100000");
  if (black_from < -1 || black_from > 100000) return outOfRange("black_from", "in -1..100000");
  if (black_to < -1 || black_to > 100000) return outOfRange("black_to", "in -1..100000");
  if (width < 32 || width > 8192) return outOfRange("width", "in 32..8192");
  if (height < 32 || height > 8192) return outOfRange("height", "in 32..8192");
  if (!inRange(baseline_m, 1e-6, 100.0)) return outOfRange("baseline_m", "in (0, 100]");
  if (!inRange(hfov_deg, 10.0, 150.0)) return outOfRange("hfov_deg", "in [10, 150]");
  if (!inRange(rate_hz, 1e-6, 10000.0)) return outOfRange("rate_hz", "in (0, 10000]");
  if (!inRange(relief_m, 0.0, 1000.0)) return outOfRange("relief_m", "in [0, 1000]");
  if (!inRange(terrain_cell_m, 1.0, 10000.0)) return outOfRange("terrain_cell_m", "in [1, 10000]");
  if (variant == FlightVariant::kBlimp) {
    if (!inRange(altitude_min_m, 20.0, 35.0)) return outOfRange("altitude_min_m", "in [20, 35]");
    if (!inRange(altitude_max_m, altitude_min_m, 35.0))
      return outOfRange("altitude_max_m", "in [altitude_min_m, 35]");
    if (altitude_min_m < relief_m + 5.0)
      return outOfRange("altitude_min_m", ">= relief_m + 5 (clear of the ground)");
  }
  if (!inRange(camera_height_m, 0.2, 20.0)) return outOfRange("camera_height_m", "in [0.2, 20]");
  if (!inRange(camera_pitch_deg, 0.0, 90.0)) return outOfRange("camera_pitch_deg", "in [0, 90]");
  if (!inRange(loop_length_m, 1.0, 2000.0)) return outOfRange("loop_length_m", "in [1, 2000]");
  if (!inRange(loop_aspect, 0.1, 1.0)) return outOfRange("loop_aspect", "in [0.1, 1]");
  if (!(texture_period_m == 0.0 || inRange(texture_period_m, 5.0, 1e4)))
    return outOfRange("texture_period_m", "0 or in [5, 10000]");
  if (!inRange(wobble_deg, 0.0, 20.0)) return outOfRange("wobble_deg", "in [0, 20]");
  if (!inRange(wobble_period_s, 1e-3, 1e6)) return outOfRange("wobble_period_s", "in [0.001, 1e6]");
  if (!inRange(noise_sigma, 0.0, 50.0)) return outOfRange("noise_sigma", "in [0, 50]");
  if (!inRange(max_range_m, 1.0, 1e6)) return outOfRange("max_range_m", "in [1, 1e6]");
  if (!inRange(haze_m, 1.0, 1e9)) return outOfRange("haze_m", "in [1, 1e9]");
  if (supersample < 1 || supersample > 4) return outOfRange("supersample", "in 1..4");
  return Status::ok();
}

SyntheticFlight::SyntheticFlight(const SyntheticFlightParams& p)
    : params_(p),
      terrain_(p.relief_m, p.terrain_cell_m, p.seed),
      albedo_(synth::mix64(p.seed) ^ 0xA1BEDu),
      sun_W_(Eigen::Vector3d(0.45, 0.3, 0.84).normalized()) {
  calib_.width = p.width;
  calib_.height = p.height;
  calib_.f_px = 0.5 * p.width / std::tan(0.5 * p.hfov_deg * kDeg);
  calib_.cx_px = 0.5 * (p.width - 1);
  calib_.cy_px = 0.5 * (p.height - 1);
  calib_.baseline_m = p.baseline_m;
  calib_.exact = true;  // the renderer projects with exactly this calibration
  period_ns_ = static_cast<TimeNs>(std::llround(1e9 / p.rate_hz));
  semi_a_m_ = p.loop_length_m / unitEllipsePerimeter(p.loop_aspect);
  semi_b_m_ = p.loop_aspect * semi_a_m_;
  const std::uint64_t h = synth::mix64(p.seed ^ 0x5EEDull);
  roll_phase_ = 2.0 * kPi * static_cast<double>(h >> 40) / 16777216.0;
  pitch_phase_ = 2.0 * kPi * static_cast<double>(h & 0xFFFFFFu) / 16777216.0;
}

Result<SyntheticFlight> SyntheticFlight::create(const SyntheticFlightParams& params) {
  if (Status s = params.validate(); !s) return s;
  return SyntheticFlight(params);
}

Eigen::Isometry3d SyntheticFlight::pose(int index) const {
  const auto& p = params_;
  const int loop = p.loop_frames > 0 ? p.loop_frames : p.frames;
  const double theta = 2.0 * kPi * static_cast<double>(index % loop) / loop;
  const double t_s = static_cast<double>(index) / p.rate_hz;
  Eigen::Vector3d pos(semi_a_m_ * std::cos(theta), semi_b_m_ * std::sin(theta), 0.0);
  if (p.variant == FlightVariant::kBlimp) {
    pos.z() = 0.5 * (p.altitude_min_m + p.altitude_max_m) +
              0.5 * (p.altitude_max_m - p.altitude_min_m) * std::sin(theta);
  } else {
    pos.z() = heightAt(pos.x(), pos.y()) + p.camera_height_m;
  }
  // Heading along the tangent (-a sin, b cos) of the counter-clockwise ellipse.
  const double yaw = std::atan2(semi_b_m_ * std::cos(theta), -semi_a_m_ * std::sin(theta));
  const double w = p.wobble_deg * kDeg;
  const double roll = w * std::sin(2.0 * kPi * t_s / p.wobble_period_s + roll_phase_);
  const double pitch = w * std::sin(2.0 * kPi * t_s / (1.37 * p.wobble_period_s) + pitch_phase_);
  const Eigen::Matrix3d R_W_B = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                                 Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                                 Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
                                    .toRotationMatrix();
  // Camera axes in the body frame (x forward, y left, z up), tilted down by alpha.
  const double a = p.camera_pitch_deg * kDeg;
  Eigen::Matrix3d R_B_C;
  R_B_C.col(0) = Eigen::Vector3d(0.0, -1.0, 0.0);
  R_B_C.col(1) = Eigen::Vector3d(-std::sin(a), 0.0, -std::cos(a));
  R_B_C.col(2) = Eigen::Vector3d(std::cos(a), 0.0, -std::sin(a));
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R_W_B * R_B_C;
  T.translation() = pos;
  return T;
}

Eigen::Isometry3d SyntheticFlight::rightPose(int index) const {
  return pose(index) * Eigen::Translation3d(params_.baseline_m, 0.0, 0.0);
}

bool SyntheticFlight::intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_guess,
                                double& t_hit, double* dz_dx, double* dz_dy) const {
  // Slab half-height padded so that flat ground (relief 0) still gives lo < hi.
  const double H = terrain_.maxAbsHeight() + 1e-6, L = terrain_.slopeBound();
  const double d_xy = std::sqrt(d.x() * d.x() + d.y() * d.y());
  const double t_max = params_.max_range_m / d.norm();
  double gx = 0.0, gy = 0.0;  // slope at the last evaluation
  // g(t) = height of the ray above the ground; g'(t) = d_z - grad h . d_xy.
  auto g = [&](double t, double& dg) {
    const double h = terrain_.height(o.x() + t * d.x(), o.y() + t * d.y(), gx, gy);
    dg = d.z() - (gx * d.x() + gy * d.y());
    return o.z() + t * d.z() - h;
  };
  // The ray is inside the slab |z| <= H for t in [lo, hi].
  double lo = 0.0, hi = t_max;
  if (d.z() < 0.0) {
    lo = std::max(0.0, (o.z() - H) / -d.z());
    hi = std::min(t_max, (o.z() + H) / -d.z());
  } else if (o.z() >= H) {
    return false;
  }
  if (!(lo < hi)) return false;
  double dg = 0.0;
  // Lower bound of g': g decreases by at most `descent` per unit t.
  const double descent = std::max(-d.z(), 0.0) + L * d_xy;
  if (d.z() + L * d_xy < 0.0) {
    // g strictly decreasing: one root at most. g(lo) >= 0 unless the camera is underground.
    if (hi < (o.z() + H) / -d.z() && g(hi, dg) > 0.0) return false;  // beyond max_range_m
    if (lo == 0.0 && g(0.0, dg) <= 0.0) return false;
  } else {
    // March with Lipschitz-safe steps until g changes sign, which brackets the first root.
    double t = lo, gv = g(t, dg);
    if (gv <= 0.0) {
      if (lo == 0.0) return false;  // camera underground
      t_hit = t;
      if (dz_dx != nullptr) *dz_dx = gx, *dz_dy = gy;
      return true;
    }
    for (;;) {
      const double safe = descent > 0.0 ? gv / descent : std::numeric_limits<double>::infinity();
      const double t_next = std::min(hi, t + std::max(safe, 0.015 * t + 1e-3));
      const double g_next = g(t_next, dg);
      if (g_next <= 0.0) {
        lo = t;
        hi = t_next;
        break;
      }
      if (t_next >= hi) return false;
      t = t_next;
      gv = g_next;
    }
    t_guess = -1.0;
  }
  // Safeguarded Newton in [lo, hi] with g(lo) > 0 >= g(hi). After a step delta from t,
  // g(t + delta) = g''(xi) delta^2 / 2 with |g''| <= M = K |d_xy|^2 (K the terrain curvature
  // bound), so the root is within M delta^2 / (2 |g'|) of t + delta: the step is taken without
  // another evaluation once that is below kDepthTol_m.
  const double M = terrain_.curvatureBound() * d_xy * d_xy;
  double t = (t_guess > lo && t_guess < hi) ? t_guess : 0.5 * (lo + hi);
  for (int it = 0; it < 200; ++it) {
    const double gv = g(t, dg);
    if (gv == 0.0) break;
    (gv > 0.0 ? lo : hi) = t;
    double tn = dg < 0.0 ? t - gv / dg : -1.0;
    const bool newton_ok = tn > lo && tn < hi;
    if (newton_ok && 0.5 * M * (tn - t) * (tn - t) <= kDepthTol_m * -dg) {
      t = tn;
      break;
    }
    if (!newton_ok) tn = 0.5 * (lo + hi);
    if (hi - lo <= 1e-12 * hi) {
      t = tn;
      break;
    }
    t = tn;
  }
  t_hit = t;
  if (dz_dx != nullptr) *dz_dx = gx, *dz_dy = gy;
  return true;
}

struct SyntheticFlight::View {
  Eigen::Vector3d o_W;    // camera centre
  Eigen::Matrix3d R_W_C;  // camera axes in the world
  std::uint64_t noise_key = 0;
};

double SyntheticFlight::shadeRay(const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                                 RayHistory& history) const {
  const double d_norm = d.norm();
  double t = 0.0, gx = 0.0, gy = 0.0;
  if (!intersect(o, d, history.guess(), t, &gx, &gy)) {
    history.push(-1.0);
    return skyAt(d.z() / d_norm);
  }
  history.push(t);
  const Eigen::Vector3d p = o + t * d;
  const Eigen::Vector3d n = Eigen::Vector3d(-gx, -gy, 1.0).normalized();
  // Footprint of one (sub)pixel on the ground: distance / f, stretched by the incidence
  // (cos clamped so grazing ground blurs instead of aliasing).
  const double dist = t * d_norm;
  const double cos_inc = std::max(std::fabs(n.dot(d)) / d_norm, 0.15);
  const double fp_m = dist / (calib_.f_px * params_.supersample * cos_inc);
  const double lambert = std::max(n.dot(sun_W_), 0.0) / sun_W_.z();  // 1 on flat ground
  double ax = p.x(), ay = p.y();
  if (params_.texture_period_m > 0.0) {  // look-alike places (the seam is a texture edge)
    const double P = params_.texture_period_m;
    ax -= P * std::floor(ax / P);
    ay -= P * std::floor(ay / P);
  }
  const double v = albedo_.at(ax, ay, fp_m) * (0.3 + 0.7 * lambert);
  const double horizon = skyAt(0.0);
  return horizon + (v - horizon) * std::exp(-dist / params_.haze_m);
}

void SyntheticFlight::renderRows(const View& view, int y0, int y1, ImageU8* image,
                                 ImageF32* depth) const {
  const int W = params_.width, s = params_.supersample;
  const double inv_f = 1.0 / calib_.f_px;
  auto ray = [&](double u, double v) {
    return Eigen::Vector3d(
        view.R_W_C * Eigen::Vector3d((u - calib_.cx_px) * inv_f, (v - calib_.cy_px) * inv_f, 1.0));
  };
  for (int y = y0; y < y1; ++y) {
    // Each row starts from scratch, so stripes give identical bytes.
    RayHistory centre, sub[16];
    for (int x = 0; x < W; ++x) {
      if (image != nullptr) {
        double sum = 0.0;
        for (int k = 0; k < s * s; ++k) {
          const double du = ((k % s) + 0.5) / s - 0.5, dv = ((k / s) + 0.5) / s - 0.5;
          sum += shadeRay(view.o_W, ray(x + du, y + dv), sub[k]);
        }
        double v = sum / (s * s);
        if (params_.noise_sigma > 0.0) {
          const std::uint64_t h = synth::mix64(
              view.noise_key ^ (static_cast<std::uint64_t>(y) * static_cast<std::uint64_t>(W) +
                                static_cast<std::uint64_t>(x)));
          v += params_.noise_sigma * gaussianFromHash(h);
        }
        (*image)(x, y) = static_cast<std::uint8_t>(std::lround(std::clamp(v, 0.0, 255.0)));
      }
      if (depth == nullptr) continue;
      if (image == nullptr || s != 1) {
        double t = 0.0;
        centre.push(intersect(view.o_W, ray(x, y), centre.guess(), t) ? t : -1.0);
      } else {
        centre = sub[0];
      }
      (*depth)(x, y) =
          centre.t1 > 0.0 ? static_cast<float>(centre.t1) : std::numeric_limits<float>::infinity();
    }
  }
}

Status SyntheticFlight::render(int index, ImageU8& left, ImageU8& right,
                               ImageF32* depth_left) const {
  SerialExecutor serial;
  return render(index, left, right, depth_left, serial);
}

Status SyntheticFlight::render(int index, ImageU8& left, ImageU8& right, ImageF32* depth_left,
                               Executor& executor) const {
  if (index < 0 || index >= params_.frames)
    return Status::invalidArgument("synthetic flight: frame index " + std::to_string(index) +
                                   " outside 0.." + std::to_string(params_.frames - 1));
  const int W = params_.width, H = params_.height;
  left.resize(W, H);
  right.resize(W, H);
  if (depth_left != nullptr) depth_left->resize(W, H);
  const Eigen::Isometry3d T_l = pose(index), T_r = rightPose(index);
  const std::uint64_t key = synth::mix64(params_.seed ^ synth::mix64(0xF00Dull + index));
  const View views[2] = {{T_l.translation(), T_l.linear(), synth::mix64(key)},
                         {T_r.translation(), T_r.linear(), synth::mix64(key + 1)}};
  // Tasks: (camera, row stripe); 16 stripes per camera.
  constexpr int kStripes = 16;
  executor.parallelFor(2 * kStripes, [&](int task) {
    const int cam = task / kStripes, stripe = task % kStripes;
    const int y0 = H * stripe / kStripes, y1 = H * (stripe + 1) / kStripes;
    renderRows(views[cam], y0, y1, cam == 0 ? &left : &right, cam == 0 ? depth_left : nullptr);
  });
  return Status::ok();
}

Status SyntheticFlight::renderDepth(int index, ImageF32& depth_left) const {
  if (index < 0 || index >= params_.frames)
    return Status::invalidArgument("synthetic flight: frame index " + std::to_string(index) +
                                   " outside 0.." + std::to_string(params_.frames - 1));
  depth_left.resize(params_.width, params_.height);
  const Eigen::Isometry3d T = pose(index);
  renderRows(View{T.translation(), T.linear(), 0}, 0, params_.height, nullptr, &depth_left);
  return Status::ok();
}

Status SyntheticFlight::trueDisparity(int index, ImageF32& disparity_px) const {
  if (Status s = renderDepth(index, disparity_px); !s) return s;
  const double fb = calib_.f_px * calib_.baseline_m;
  for (int y = 0; y < params_.height; ++y)
    for (int x = 0; x < params_.width; ++x) {
      const float z = disparity_px(x, y);
      disparity_px(x, y) = std::isfinite(z) ? static_cast<float>(fb / z) : 0.0f;
    }
  return Status::ok();
}

}  // namespace svslam::drivers
