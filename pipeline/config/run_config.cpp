#include "pipeline/config/run_config.hpp"

#include "pipeline/config/config_keys.hpp"
#include "pipeline/config/yaml_config.hpp"

namespace svslam::config {
namespace {

std::string fullName(const ConfigSection& s, const ConfigKey& k) {
  return s.name.empty() ? k.name : s.name + "." + k.name;
}

// A key of an earlier version, named with its new name.
Status checkRenamedKeys(const ConfigReader& r) {
  for (const RenamedKey& k : renamedConfigKeys())
    if (r.has(k.old_name))
      return Status::invalidArgument(r.name() + ": key '" + k.old_name + "' was renamed to '" +
                                     k.new_name + "'");
  return Status::ok();
}

// The checks that involve several keys (each key's own range is checked when read).
Status checkAcrossKeys(const std::string& file, const RunConfig& c) {
  const StereoOdometryParams& o = c.odometry;
  if (o.stereo_match.max_disp_px <= o.stereo_match.min_disp_px)
    return Status::invalidArgument(file + ": key 'stereo_match.max_disp_px' must be > min_disp_px");
  if (o.dense) {
    if (Status s = o.dense_stereo.validate(); !s)
      return Status::invalidArgument(file + ": dense_stereo: " + s.message());
  }
  SVSLAM_TRY(checkPipelineConfig(file, c.pipeline, c.lcm));
  if (Status s = o.validate(); !s) return Status::invalidArgument(file + ": " + s.message());
  if (Status s = c.slam.validate(); !s) return Status::invalidArgument(file + ": " + s.message());
  if (Status s = c.dem.validate(); !s) return Status::invalidArgument(file + ": " + s.message());
  return Status::ok();
}

Status parse(ConfigReader& r, RunConfig& out) {
  SVSLAM_TRY(checkRenamedKeys(r));
  for (const ConfigSection& s : allConfigSections())
    for (const ConfigKey& k : s.keys) SVSLAM_TRY(k.read(r, fullName(s, k), out));
  SVSLAM_TRY(r.finish());
  out.odometry.motion.seed = out.seed;
  out.slam.bearing_init.seed = out.seed;
  out.slam.two_view.seed = out.seed;
  applyThreads(out, out.threads);
  return checkAcrossKeys(r.name(), out);
}

}  // namespace

const char* toString(EstimatorMode m) { return nameOf(kEstimatorModeNames, m); }

void applyThreads(RunConfig& cfg, int threads) {
  cfg.threads = threads;
  cfg.odometry.dense_stereo.num_stripes = threads;
}

Status parseRunConfig(const std::string& yaml_text, const std::string& name, RunConfig& out,
                      std::set<std::string>* changed_keys) {
  auto r = ConfigReader::fromString(yaml_text, name);
  if (!r) return r.status();
  const Status s = parse(*r, out);
  if (changed_keys) *changed_keys = r->changedKeys();
  return s;
}

Status loadRunConfig(const std::string& path, RunConfig& out, std::set<std::string>* changed_keys) {
  if (path.empty()) {
    if (changed_keys) changed_keys->clear();  // no file: nothing changes a default
    ConfigReader r;
    return parse(r, out);
  }
  auto r = ConfigReader::fromFile(path);
  if (!r) return r.status();
  const Status s = parse(*r, out);
  if (changed_keys) *changed_keys = r->changedKeys();
  return s;
}

}  // namespace svslam::config
