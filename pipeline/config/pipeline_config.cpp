#include "pipeline/config/pipeline_config.hpp"

#include <cmath>

#include "pipeline/config/yaml_config.hpp"

namespace svslam::config {
namespace {

Status readScheduling(ConfigReader& r, const std::string& stage, service::ThreadScheduling& t) {
  const std::string key = "pipeline.scheduling." + stage;
  std::vector<double> cpus;
  SVSLAM_TRY(r.read(key + ".cpus", cpus));
  t.cpus.clear();
  for (double c : cpus) {
    if (!(c >= 0 && c <= 1023 && c == std::floor(c)))
      return Status::invalidArgument(r.name() + ": key '" + key +
                                     ".cpus' holds a value that is not a CPU index (0..1023)");
    t.cpus.push_back(static_cast<int>(c));
  }
  SVSLAM_TRY(r.read(key + ".fifo_priority", t.fifo_priority, 0, 99));
  if (Status s = t.validate(); !s) return Status::invalidArgument(r.name() + ": " + key + ": " + s.message());
  return Status::ok();
}

}  // namespace

Status readPipelineConfig(ConfigReader& r, PipelineConfig& p, LcmConfig& l, ServiceConfig& s) {
  SVSLAM_TRY(r.read("pipeline.sequential", p.sequential));
  SVSLAM_TRY(r.read("pipeline.rate_hz", p.rate_hz, 0, 10000));
  SVSLAM_TRY(r.read("pipeline.capture_policy", p.capture_policy, {"auto", "newest", "block"}));
  SVSLAM_TRY(r.read("pipeline.queue_capacity", p.queue_capacity, 1, 64));
  SVSLAM_TRY(r.read("pipeline.preload", p.preload));
  SVSLAM_TRY(r.read("pipeline.progress_period_s", p.progress_period_s, 0, 1e6));
  SVSLAM_TRY(readScheduling(r, "capture", p.capture));
  SVSLAM_TRY(readScheduling(r, "stereo", p.stereo));
  SVSLAM_TRY(readScheduling(r, "estimator", p.estimator));
  SVSLAM_TRY(readScheduling(r, "publisher", p.publisher));
  SVSLAM_TRY(r.read("lcm.enabled", l.enabled));
  SVSLAM_TRY(r.read("lcm.url", l.params.url));
  SVSLAM_TRY(r.read("lcm.pose_channel", l.params.pose_channel));
  SVSLAM_TRY(r.read("lcm.stats_channel", l.params.stats_channel));
  SVSLAM_TRY(r.read("lcm.map_channel", l.params.map_channel));
  SVSLAM_TRY(r.read("lcm.command_channel", l.params.command_channel));
  SVSLAM_TRY(r.read("lcm.status_channel", l.params.status_channel));
  SVSLAM_TRY(r.read("lcm.stats_period_s", l.stats_period_s, 0.01, 3600));
  if (Status st = l.params.validate(); !st)
    return Status::invalidArgument(r.name() + ": lcm: " + st.message());
  SVSLAM_TRY(r.read("service.ready", s.ready, {"first_pose", "start"}));
  SVSLAM_TRY(r.read("service.stall_timeout_s", s.stall_timeout_s, 0.1, 3600));
  return Status::ok();
}

}  // namespace svslam::config
