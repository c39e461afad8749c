#pragma once
// Shared pieces of the tests that drive the real-time pipeline with a scripted work object.
#include <memory>
#include <vector>

#include "pipeline/realtime/pipeline_runner.hpp"

namespace svslam::rt {

// The four stages capture -> stereo -> estimator -> publisher, calling the members capture,
// stereo, estimate and publish of `w`; `capture_input`: the policy of the edge capture -> stereo.
template <typename Work>
StageGraph fourStageGraph(Work& w, EdgePolicy capture_input = EdgePolicy::kBlocking) {
  StageGraph g;
  g.source = {"capture", [&w](FrameSlot& s) { return w.capture(s); }};
  g.stages = {{"stereo", [&w](FrameSlot& s) { return w.stereo(s); }, capture_input},
              {"estimator", [&w](FrameSlot& s) { return w.estimate(s); }},
              {"publisher", [&w](FrameSlot& s) { return w.publish(s); }}};
  return g;
}

// As many empty slots as `runner` needs.
inline std::vector<std::unique_ptr<FrameSlot>> makeSlots(const PipelineRunner& runner) {
  std::vector<std::unique_ptr<FrameSlot>> s;
  for (int i = 0; i < runner.slotsNeeded(); ++i) s.push_back(std::make_unique<FrameSlot>());
  return s;
}

}  // namespace svslam::rt
