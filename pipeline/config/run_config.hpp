#pragma once
// The configuration of `svslam run`. Every key is optional; defaults are the struct defaults
// below and those of the component parameter structs. Each key is declared once, with its unit,
// range and doc, in run_config_keys.cpp / pipeline_config_keys.cpp; the reader and
// `svslam config --defaults` (which prints config/svslam.yaml) derive from those tables.
// Unknown keys, renamed keys and out-of-range values are rejected with a message naming the key.
#include <array>
#include <cstdint>
#include <optional>
#include <set>
#include <string>

#include "core/status.hpp"
#include "loop/loop_closer.hpp"
#include "map/dem_params.hpp"
#include "odometry/stereo_odometry.hpp"
#include "pipeline/config/enum_names.hpp"
#include "pipeline/config/pipeline_config.hpp"
#include "slam/estimator.hpp"
#include "slam/slam_params.hpp"

namespace svslam::config {

// kEkf: EKF SLAM over pose and landmarks; kVo: pure visual odometry; kMono: EKF SLAM from the
// left camera, scale from the first pair (slam/estimator.hpp).
using EstimatorMode = EstimatorKind;
inline constexpr EnumNames<EstimatorMode, 3> kEstimatorModeNames{
    {{"ekf", EstimatorMode::kEkf}, {"vo", EstimatorMode::kVo}, {"mono", EstimatorMode::kMono}}};
const char* toString(EstimatorMode m);

inline StereoOdometryParams runOdometryDefaults() {
  StereoOdometryParams p;
  p.dense = true;
  p.dense_stereo.max_disp = 128;
  return p;
}

struct RunConfig {
  std::string source = "synthetic";  // source specification (drivers/source/stereo_source.hpp)
  int max_frames = 0;                // 0 = the whole sequence
  int threads = 1;                   // worker threads of the stages that split work
  std::uint64_t seed = 1;            // seeds every random choice (RANSAC)
  EstimatorMode mode = EstimatorMode::kEkf;
  // The library's defaults, except dense stereo: on in a run (it feeds the map and the EKF's
  // 8-neighbour observation), searching 0..127 px.
  StereoOdometryParams odometry = runOdometryDefaults();
  SlamSystemParams slam;
  PipelineConfig pipeline;  // pipeline.*: threads, queues, pacing, scheduling
  LcmConfig lcm;            // lcm.*: publishing and commands
  ServiceConfig service;    // service.*: systemd life cycle
  // map.*: the elevation map (seed 001 sec 5.2; src/map/dem_params.hpp, map_frame.hpp).
  bool map_enabled = true;  // the mapper stage runs
  map::DemParams dem;
  // Geodetic position of the map origin (WGS84 latitude, longitude in degrees, ellipsoidal
  // altitude in metres) for georeferenced outputs; nullopt: the map stays in local metres.
  std::optional<std::array<double, 3>> map_geo_origin;
  double map_publish_period_s = 1.0;  // map tiles changed since the last period go to LCM, s
  // With loop closing: after a new solution, the map is re-placed during the flight at most
  // this often (MapStage::replaceLive), s; 0 = only at the end of the run.
  double map_replace_period_s = 10.0;
  // loop.*: loop closing (src/loop/loop_closer.hpp): keyframes, place recognition with the
  // vocabulary file loop_vocabulary (`svslam train-vocabulary`), verification, PCM, pose graph.
  bool loop_enabled = false;
  std::string loop_vocabulary;
  LoopCloserParams loop;
  // The estimator moves into the back end's corrected frame (Estimator::moveWorld) before the
  // frame loop_feedback_delay_frames after the keyframe whose solution gave the correction
  // (pipeline/realtime/loop_stage.hpp).
  bool loop_feedback = true;
  int loop_feedback_delay_frames = 5;
};

// Sets the worker threads and everything that follows them (the dense stereo stripes).
void applyThreads(RunConfig& cfg, int threads);

// Reads `path` (empty: defaults only) into `out`. With `changed_keys`, also the keys of the file
// whose value differs from what `out` held (into a default RunConfig: the keys that change a
// default).
Status loadRunConfig(const std::string& path, RunConfig& out,
                     std::set<std::string>* changed_keys = nullptr);
// Same, from YAML text (tests).
Status parseRunConfig(const std::string& yaml_text, const std::string& name, RunConfig& out,
                      std::set<std::string>* changed_keys = nullptr);

// Every key with the value it has in `cfg`, section by section, each with a comment giving its
// range or choices, unit and meaning. Reads back to the same values (floats exactly).
std::string formatRunConfig(const RunConfig& cfg);
// What `svslam config --defaults` prints (config/svslam.yaml): a header of comment lines, then
// formatRunConfig(RunConfig{}).
std::string defaultsYaml();

}  // namespace svslam::config
