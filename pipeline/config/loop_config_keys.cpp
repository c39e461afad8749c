// The keys of the loop section (loop closing: RunConfig::loop_enabled, loop_vocabulary, loop):
// field, unit, range and doc of each, once.
#include "pipeline/config/config_keys.hpp"

namespace svslam::config {

ConfigSection loopConfigSection() {
  ConfigSection s{"loop", "loop closing: keyframes, place recognition, pose graph (src/loop/)", {}};
  s.keys = {
      flag("enabled", SVSLAM_FIELD(loop_enabled),
           "true: keyframes are indexed and loops closed by a pose-graph back end (needs "
           "dense_stereo.enabled and vocabulary)"),
      text("vocabulary", SVSLAM_FIELD(loop_vocabulary),
           "binary vocabulary file made by `svslam train-vocabulary`"),
      number("travel_depth_fraction", SVSLAM_FIELD(loop.keyframe.travel_depth_fraction), 1e-3, 10,
             "", "new keyframe after travelling this fraction of the last keyframe's median depth"),
      number("min_rotation_deg", SVSLAM_FIELD(loop.keyframe.min_rotation_deg), 0.1, 180, "deg",
             "... or after this rotation"),
      number("keyframe_points", SVSLAM_FIELD(loop.keyframe.max_points), 16, 2000, "",
             "ORB points with 3D kept per keyframe (76 bytes each)"),
      number("min_normalised_score", SVSLAM_FIELD(loop.place.min_normalised_score), 0, 100, "",
             "place score / score against the previous keyframe needed for a candidate"),
      number("exclude_recent", SVSLAM_FIELD(loop.place.exclude_recent), 0, 100000, "",
             "the last this many keyframes are never loop candidates"),
      number("temporal_consistency", SVSLAM_FIELD(loop.place.temporal_consistency), 1, 100, "",
             "consecutive keyframes whose best places agree before a candidate is verified"),
      number("min_inliers", SVSLAM_FIELD(loop.verify.min_inliers), 6, 10000, "",
             "3D-3D inliers of the geometric verification"),
      number("min_consistent_loops", SVSLAM_FIELD(loop.min_consistent_loops), 1, 100, "",
             "mutually consistent loops (PCM) before any is used"),
      number("filter_edge_chi2", SVSLAM_FIELD(loop.filter_edge_chi2), 0, 1e6, "",
             "> 0: odometry edges take the filter's relative pose when within this chi-square "
             "(6 dof) of the motion chain; 0: always the motion chain"),
      number("pair_chi2", SVSLAM_FIELD(loop.consistency.pair_chi2), 1e-3, 1e6, "",
             "chi-square (6 dof) bound of a loop pair's cycle through the odometry"),
      number("max_solve_keyframes", SVSLAM_FIELD(loop.max_solve_keyframes), 0, 10000000, "",
             "a solve moves only the newest this many keyframes (older ones held at their last "
             "solution): bounds its time on long flights; 0 = the whole graph"),
      flag("feedback", SVSLAM_FIELD(loop_feedback),
           "true: after a solution the estimator (pose, landmarks of the state and their "
           "covariance) moves into the corrected frame; false: only the outputs and the LCM "
           "correction message are corrected"),
      number("feedback_delay_frames", SVSLAM_FIELD(loop_feedback_delay_frames), 1, 1000, "",
           "a solution made at a keyframe moves the estimator before the frame this many "
           "frames later (replayed as fast as possible the estimator waits for it there, so "
           "the output does not depend on thread timing; live, it is applied when ready)"),
      number("wrong_loop_fraction", SVSLAM_FIELD(loop.wrong_loop_fraction), 0, 0.5, "",
             "test hook: share of verified loops re-attached to a wrong keyframe (seeded by "
             "seed); 0 in any real use"),
  };
  return s;
}

}  // namespace svslam::config
