#pragma once
// The four figures of `svslam plot` from the contents of a run folder (already read and, for
// the ground truth, already aligned): trajectory top view, altitude against time, landmarks,
// per-stage times.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/status.hpp"
#include "drivers/files/run_files.hpp"
#include "eval/plot_scales.hpp"
#include "pipeline/tools/plot/plot_scene.hpp"

namespace svslam::plot {

struct RunPlotData {
  std::string run_name;                // shown in the titles
  std::vector<double> t_s;             // per estimated pose, seconds since the first
  std::vector<Eigen::Vector3d> p_est;  // estimated camera positions, run world frame, m
  std::vector<Eigen::Matrix3d> cov_p;  // per estimated pose, its position covariance (m^2);
                                       // empty: no pose_covariance.txt
  std::vector<Eigen::Vector3d> p_gt;   // ground-truth positions in the run frame (all of them)
  std::vector<double> t_gt_s;          // their times (same clock as t_s); empty: unknown
  std::string gt_label;                // legend of the ground truth
  bool has_landmarks = false;
  std::vector<drivers::LandmarkPoint> landmarks;
  bool has_stages = false;
  std::vector<drivers::StageTimeSummary> stages;  // stats.json "stage_ms"
  bool has_latency_log = false;
  std::vector<double> latency_ms;  // latency.txt, end to end per published frame
};

struct PlotSettings {
  HorizontalFrame frame;  // top-view axes and the up direction
  int ellipse_every = 0;  // a 2-sigma ellipse every this many poses; 0: about 20 along the run
  int width_px = 800, height_px = 600;
};

// Number of ellipses drawn (poses with a non-zero horizontal covariance) comes back in
// `ellipses`. Error when a covariance is not a covariance (not symmetric, not PSD).
Result<Figure> trajectoryTopFigure(const RunPlotData& d, const PlotSettings& s, int* ellipses);
Figure altitudeFigure(const RunPlotData& d, const PlotSettings& s);
Figure landmarksFigure(const RunPlotData& d, const PlotSettings& s);
Figure latencyFigure(const RunPlotData& d, const PlotSettings& s);

}  // namespace svslam::plot
