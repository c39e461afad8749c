#pragma once
// Reading back the files of a `svslam run` output folder that trajectory_io does not cover
// (for `svslam plot`): pose_covariance.txt, landmarks.ply, the per-stage times of stats.json and
// latency.txt. Errors name the file (and the line where there is one).
#include <Eigen/Core>
#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "core/status.hpp"

namespace svslam::drivers {

using PoseCovariance = Eigen::Matrix<double, 6, 6>;

// pose_covariance.txt: 36 finite numbers per non-blank line, the 6x6 covariance of a pose,
// row-major, [rot (rad), trans (m)], one line per trajectory line.
Result<std::vector<PoseCovariance>> readPoseCovariances(const std::string& path);

// A landmark of landmarks.ply (world frame, metres).
struct LandmarkPoint {
  Eigen::Vector3d p_world = Eigen::Vector3d::Zero();
  bool active = false;  // in the filter state at the end (else retired); false when absent
};
// ASCII PLY with a "vertex" element that has x, y, z (float/double) and optionally "active".
Result<std::vector<LandmarkPoint>> readLandmarksPly(const std::string& path);

// One entry of stats.json's "stage_ms" object: the algorithm stage's duration summary.
struct StageTimeSummary {
  std::string stage;
  double p50_ms = 0, p99_ms = 0, max_ms = 0;  // NaN when stats.json holds none (null / nan)
  std::int64_t count = 0;
};
// The "stage_ms" object of stats.json, in file order. Error when the file is not JSON or has no
// "stage_ms" object.
Result<std::vector<StageTimeSummary>> readStageTimes(const std::string& stats_json_path);

// latency.txt (pipeline.latency_log): "seq ms" per published frame; returns the ms column.
Result<std::vector<double>> readLatencyLog(const std::string& path);

// The files of `svslam plot`, each written to "<path>.tmp" and renamed: an 8-bit BGR image as
// PNG, and a text (the SVG).
Status writePlotPng(const std::string& path, const cv::Mat& bgr);
Status writePlotText(const std::string& path, const std::string& text);

}  // namespace svslam::drivers
