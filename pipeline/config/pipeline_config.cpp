#include "pipeline/config/pipeline_config.hpp"

namespace svslam::config {

const char* toString(CapturePolicy p) { return nameOf(kCapturePolicyNames, p); }
const char* toString(ReadyWhen r) { return nameOf(kReadyWhenNames, r); }
const char* toString(FaultStage f) { return nameOf(kFaultStageNames, f); }

Status checkPipelineConfig(const std::string& file, const PipelineConfig& p, const LcmConfig& l) {
  const std::pair<const char*, const service::ThreadScheduling*> stages[] = {
      {"capture", &p.capture},
      {"stereo", &p.stereo},
      {"estimator", &p.estimator},
      {"publisher", &p.publisher},
      {"mapper", &p.mapper}};
  for (const auto& [stage, t] : stages)
    if (Status s = t->validate(); !s)
      return Status::invalidArgument(file + ": pipeline.scheduling." + stage + ": " + s.message());
  if (Status s = l.params.validate(); !s)
    return Status::invalidArgument(file + ": lcm: " + s.message());
  if (Status s = l.commands.validate(); !s)
    return Status::invalidArgument(file + ": " + s.message());
  return Status::ok();
}

}  // namespace svslam::config
