#pragma once
// Parameters of the stereo visual odometry (odometry/stereo_odometry.hpp) and of its per-frame
// stereo stage (odometry/stereo_stage.hpp).
#include "core/status.hpp"
#include "features/corner_detector.hpp"
#include "features/feature_clusters.hpp"
#include "features/orb_extractor.hpp"
#include "features/stereo_point_matcher.hpp"
#include "features/temporal_matcher.hpp"
#include "motion/disparity_offset.hpp"
#include "motion/rotation_alignment.hpp"
#include "motion/visual_motion.hpp"
#include "stereo/dense_stereo.hpp"

namespace svslam {

enum class PointDetector { kCorners, kOrb };

struct StereoOdometryParams {
  PointDetector detector = PointDetector::kCorners;  // corners: precise Harris / Shi-Tomasi
                                                     // (corners.response); orb: seed 002 ORB
  CornerParams corners;
  OrbParams orb;
  StereoMatchParams stereo_match;
  TemporalMatchParams temporal_match;
  VisualMotionParams motion;
  // Online estimate of the pair's disparity offset (motion/disparity_offset.hpp): every 3D point
  // of the motion estimate and of the filter is triangulated with it.
  DisparityOffsetParams disparity_offset;
  // Clustered-feature ROI tracking (seed 004 sec 3.6): the previous frame's 3D points are
  // clustered; the clusters, moved by the predicted motion, give left ROIs (where points are
  // kept and temporally matched to their cluster's members only) and right ROIs (which bound the
  // stereo disparity search); image cells outside every ROI are unknown and keep corners down
  // to threshold_rel * unknown_threshold_factor (the detector runs at that lowered threshold,
  // corners inside ROIs must still reach threshold_rel).
  bool roi_tracking = false;
  FeatureClusterParams clusters;
  double unknown_threshold_factor = 0.25;  // (0, 1]
  bool dense = false;  // dense stereo: the disparity prior of the stereo match (and the map)
  // With dense: a point's 3D observation is the 8-neighbour combination of seed 001 sec 4.1;
  // false: the triangulation of its matched disparity (dense then only guides the match).
  bool dense_observation = true;
  DenseStereoParams dense_stereo;
  double match_sigma_px = 0.5;  // matching error between consecutive frames, px (seed 001 sec 4.1)
  double min_disparity_px = 1.0;  // points with a smaller disparity are not used, px, > 0
  double max_depth_m = 1e9;       // points farther than this are not used, m, > 0
  int min_matches = 12;           // temporal matches needed before a retry, >= 3
  float lost_search_radius_px = 100.0f;  // retry and first-pair search radius, px, > 0
  // Re-prediction of the temporal search (stereo_odometry.hpp step 1) when the constant-velocity
  // prediction is poor: rotation by image alignment, then a seeded RANSAC motion.
  bool repredict = true;
  double repredict_px = 6.0;  // median |matched - predicted| that makes a prediction poor, px, > 0
  RotationAlignmentParams rotation_alignment;
  // The motion of a frame whose search was re-predicted or retried is estimated with seeded
  // RANSAC (the other frames follow motion.ransac).
  bool ransac_on_repredict = true;
  Status validate() const;
};

}  // namespace svslam
