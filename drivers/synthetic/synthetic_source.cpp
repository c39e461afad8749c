// synthetic[:key=value,...] source (see stereo_source.hpp and synthetic_flight.hpp).
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <map>
#include <sstream>
#include <vector>

#include "drivers/source/stereo_source.hpp"
#include "drivers/synthetic/synthetic_dem.hpp"
#include "drivers/synthetic/synthetic_flight.hpp"

namespace svslam::drivers {
namespace {

class SyntheticSource final : public StereoSource {
 public:
  explicit SyntheticSource(SyntheticFlight flight) : flight_(std::move(flight)) {}
  const StereoCalibration& calibration() const override { return flight_.calibration(); }
  int size() const override { return flight_.size(); }
  Result<bool> next(StereoFrame& out) override {
    if (pos_ >= flight_.size()) return false;
    if (Status s = flight_.render(pos_, out.left, out.right); !s) return s;
    const SyntheticFlightParams& p = flight_.params();
    if (p.right_black_from >= 0 && pos_ >= p.right_black_from &&
        (p.right_black_to < 0 || pos_ < p.right_black_to))
      out.right.fill(0);
    if (p.black_from >= 0 && pos_ >= p.black_from && (p.black_to < 0 || pos_ < p.black_to)) {
      out.left.fill(0);
      out.right.fill(0);
    }
    out.index = pos_;
    out.t_ns = flight_.timeNs(pos_);
    ++pos_;
    return true;
  }
  // T_first_cam = T_W_C(0)^-1 T_W_C(index).
  bool groundTruth(int index, Eigen::Isometry3d& T_first_cam) const override {
    if (index < 0 || index >= flight_.size()) return false;
    T_first_cam = flight_.pose(0).inverse() * flight_.pose(index);
    return true;
  }
  // World gravity (0, 0, -1) (z up) in the first left camera: R_C0_W (0, 0, -1).
  bool gravityInFirstCamera(Eigen::Vector3d& g) const override {
    g = flight_.pose(0).linear().transpose() * Eigen::Vector3d(0.0, 0.0, -1.0);
    return true;
  }
  bool groundTruthDem(const Eigen::Matrix3d& R_map_world, int frames,
                      map::DemRaster& raster) const override {
    return syntheticGroundTruthDem(flight_, std::min(frames, flight_.size()), R_map_world, raster)
        .isOk();
  }
  const SyntheticFlight& flight() const { return flight_; }

 private:
  SyntheticFlight flight_;
  int pos_ = 0;
};

bool parseInt(const std::string& s, int& out) {
  const char* end = s.data() + s.size();
  auto r = std::from_chars(s.data(), end, out);
  return r.ec == std::errc() && r.ptr == end && !s.empty();
}

bool parseU64(const std::string& s, std::uint64_t& out) {
  const char* end = s.data() + s.size();
  auto r = std::from_chars(s.data(), end, out);
  return r.ec == std::errc() && r.ptr == end && !s.empty();
}

bool parseDouble(const std::string& s, double& out) {
  if (s.empty()) return false;
  char* end = nullptr;
  out = std::strtod(s.c_str(), &end);
  return end == s.c_str() + s.size() && std::isfinite(out);
}

std::vector<std::pair<std::string, std::string>> splitOptions(const std::string& options,
                                                              std::string& bad) {
  std::vector<std::pair<std::string, std::string>> kv;
  std::stringstream ss(options);
  std::string item;
  while (std::getline(ss, item, ',')) {
    if (item.empty()) continue;
    const auto eq = item.find('=');
    if (eq == std::string::npos || eq == 0) {
      bad = item;
      return {};
    }
    kv.emplace_back(item.substr(0, eq), item.substr(eq + 1));
  }
  return kv;
}

}  // namespace

Result<SyntheticFlightParams> parseSyntheticOptions(const std::string& options) {
  std::string bad;
  const auto kv = splitOptions(options, bad);
  if (!bad.empty())
    return Status::invalidArgument("synthetic source: option '" + bad + "' is not key=value");
  for (std::size_t i = 0; i < kv.size(); ++i)
    for (std::size_t j = 0; j < i; ++j)
      if (kv[i].first == kv[j].first)
        return Status::invalidArgument("synthetic source: key '" + kv[i].first +
                                       "' is given twice");
  FlightVariant variant = FlightVariant::kBlimp;
  for (const auto& [k, v] : kv)
    if (k == "variant" && !parseFlightVariant(v, variant))
      return Status::invalidArgument("synthetic source: variant must be blimp or rover, not '" + v +
                                     "'");
  SyntheticFlightParams p = SyntheticFlightParams::forVariant(variant);
  const std::map<std::string, int*> ints = {{"frames", &p.frames},
                                            {"loop_frames", &p.loop_frames},
                                            {"right_black_from", &p.right_black_from},
                                            {"right_black_to", &p.right_black_to},
                                            {"black_from", &p.black_from},
                                            {"black_to", &p.black_to},
                                            {"width", &p.width},
                                            {"height", &p.height},
                                            {"supersample", &p.supersample}};
  const std::map<std::string, double*> doubles = {{"baseline_m", &p.baseline_m},
                                                  {"hfov_deg", &p.hfov_deg},
                                                  {"rate_hz", &p.rate_hz},
                                                  {"altitude_min_m", &p.altitude_min_m},
                                                  {"altitude_max_m", &p.altitude_max_m},
                                                  {"camera_height_m", &p.camera_height_m},
                                                  {"camera_pitch_deg", &p.camera_pitch_deg},
                                                  {"loop_length_m", &p.loop_length_m},
                                                  {"loop_aspect", &p.loop_aspect},
                                                  {"texture_period_m", &p.texture_period_m},
                                                  {"wobble_deg", &p.wobble_deg},
                                                  {"wobble_period_s", &p.wobble_period_s},
                                                  {"relief_m", &p.relief_m},
                                                  {"terrain_cell_m", &p.terrain_cell_m},
                                                  {"noise_sigma", &p.noise_sigma},
                                                  {"max_range_m", &p.max_range_m},
                                                  {"haze_m", &p.haze_m}};
  for (const auto& [k, v] : kv) {
    bool ok = true;
    if (k == "variant") {
      continue;
    } else if (k == "seed") {
      ok = parseU64(v, p.seed);
    } else if (auto i = ints.find(k); i != ints.end()) {
      ok = parseInt(v, *i->second);
    } else if (auto d = doubles.find(k); d != doubles.end()) {
      ok = parseDouble(v, *d->second);
    } else {
      return Status::invalidArgument("synthetic source: unknown key '" + k + "'");
    }
    if (!ok)
      return Status::invalidArgument("synthetic source: bad value '" + v + "' for key '" + k + "'");
  }
  if (Status s = p.validate(); !s) return s;
  return p;
}

Result<std::unique_ptr<StereoSource>> openSyntheticSource(const std::string& options) {
  auto p = parseSyntheticOptions(options);
  if (!p) return p.status();
  return std::unique_ptr<StereoSource>(std::make_unique<SyntheticSource>(SyntheticFlight(*p)));
}

const SyntheticFlight* asSyntheticFlight(const StereoSource& source) {
  const auto* s = dynamic_cast<const SyntheticSource*>(&source);
  return s != nullptr ? &s->flight() : nullptr;
}

}  // namespace svslam::drivers
