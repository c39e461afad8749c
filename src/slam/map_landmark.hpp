#pragma once
// A landmark of the map: in the filter state (current estimate) or retired from it.
#include <Eigen/Core>

namespace svslam {

struct MapLandmark {
  int id = -1;
  Eigen::Vector3d p_world = Eigen::Vector3d::Zero();  // metres
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();      // m^2
  bool active = false;                                // in the filter state (else retired)
  int created_frame = 0;
  int last_seen_frame = 0;
  int observations = 0;
  bool anchored = false;  // initialised from the first frame (SlamSystem step 4)
};

}  // namespace svslam
