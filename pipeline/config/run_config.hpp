#pragma once
// The configuration of `svslam run` (documented example: config/svslam.yaml). Every key is
// optional; defaults are the struct defaults below and those of the component parameter
// structs. Unknown keys and out-of-range values are rejected with a message naming the key.
#include <cstdint>
#include <set>
#include <string>

#include "core/status.hpp"
#include "odometry/stereo_odometry.hpp"
#include "pipeline/config/pipeline_config.hpp"
#include "slam/slam_system.hpp"

namespace svslam::config {

struct RunConfig {
  std::string source = "synthetic";  // source specification (drivers/source/stereo_source.hpp)
  int max_frames = 0;                // 0 = the whole sequence
  int threads = 1;                   // worker threads of the stages that split work
  std::uint64_t seed = 1;            // seeds every random choice (RANSAC)
  std::string mode = "ekf";          // ekf (SLAM filter) | vo (pure visual odometry)
  StereoOdometryParams odometry;
  SlamSystemParams slam;
  PipelineConfig pipeline;  // pipeline.*: threads, queues, pacing, scheduling
  LcmConfig lcm;            // lcm.*: publishing and commands
  ServiceConfig service;    // service.*: systemd life cycle
};

// Reads `path` (empty: defaults only) into `out`. With `changed_keys`, also the keys of the file
// whose value differs from what `out` held (into a default RunConfig: the keys that change a
// default).
Status loadRunConfig(const std::string& path, RunConfig& out,
                     std::set<std::string>* changed_keys = nullptr);
// Same, from YAML text (tests).
Status parseRunConfig(const std::string& yaml_text, const std::string& name, RunConfig& out);

}  // namespace svslam::config
