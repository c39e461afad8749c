#pragma once
// The text files of the kitti: and euroc: layouts (stereo_source.hpp), parsed from their
// content; the sources read each file and call these. `file` names the file in errors, which
// are corruptData naming the line where there is one.
#include <Eigen/Geometry>
#include <array>
#include <string>
#include <vector>

#include "core/camera.hpp"
#include "core/status.hpp"
#include "core/time.hpp"

namespace svslam::drivers {

// KITTI calib.txt: P0 then P1, 12 finite numbers each, optionally labelled "P0:"; later lines
// are ignored. Both cameras of a rectified pair share fx, fy, cx, cy (to 1e-6 relative); P1
// holds -fx * baseline in its 4th number. Returns f_px, cx_px, cy_px, baseline_m; width and
// height stay 0 (the source takes them from the first image).
Result<StereoCalibration> parseKittiCalibration(const std::string& text, const std::string& file);

// KITTI times.txt: one stamp (seconds) per non-blank line, increasing, |t| < 9.2e9 s.
Result<std::vector<TimeNs>> parseKittiTimes(const std::string& text, const std::string& file);

// One camera of EuRoC's mav0/camN/sensor.yaml (pinhole, radial-tangential).
struct EurocSensor {
  std::array<double, 4> intrinsics{};  // fu, fv, cu, cv (px); fu, fv > 0
  std::array<double, 4> distortion{};  // k1, k2, p1, p2
  int width = 0, height = 0;           // resolution (px), integers in [1, 65536]
  Eigen::Isometry3d T_BS = Eigen::Isometry3d::Identity();  // sensor to body
};
Result<EurocSensor> parseEurocSensor(const std::string& text, const std::string& file);

// EuRoC's mav0/camN/data.csv: "timestamp,filename" lines (timestamp: decimal int64 ns; '#'
// lines are comments; trailing '\r' and spaces of the name dropped), at least one image.
struct EurocImageList {
  std::vector<TimeNs> t_ns;
  std::vector<std::string> names;  // file names under camN/data/
};
Result<EurocImageList> parseEurocDataCsv(const std::string& text, const std::string& file);

}  // namespace svslam::drivers
