#include "pipeline/run/run_summary.hpp"

#include <algorithm>

#include "pipeline/cli/json_writer.hpp"

namespace svslam::run {

using cli::JsonObject;

void RunSummary::add(int frame, const SlamFrameResult& sr) {
  const OdometryFrameResult& r = sr.odometry;
  {  // landmark counts (zero for an estimator without a map)
    sum_observed += sr.observed;
    sum_reperceived += sr.reperceived;
    sum_gated += sr.gated;
    sum_nis += sr.nis_sum;
    nis_count += sr.nis_count;
    sum_visible += sr.predicted_visible;
    sum_no_match += sr.search_no_match;
    sum_no_stereo += sr.search_no_stereo;
    sum_in_state += sr.landmarks_in_state;
    max_in_state = std::max(max_in_state, sr.landmarks_in_state);
    landmarks_in_map = sr.landmarks_in_map;
    added += sr.added;
    retired += sr.retired;
    restored += sr.restored;
    bearing_added += sr.bearing_added;
    bearing_count += sr.bearing_count;
    sum_bearing_nis += sr.bearing_nis_sum;
  }
  ++right_camera_state_counts[std::clamp(sr.right_camera, 0, 3)];
  if (sr.mono) {
    ++mono_frames;
    if (sr.initializing) ++mono_initializing;
    if (sr.altitude_scaled) altitude_scaled_frame = frame;
    if (!prev_mono_) ++right_camera_losses;
  }
  prev_mono_ = sr.mono;
  frames_lost += sr.lost ? 1 : 0;
  relocalisation_failures += sr.relocalisation_failed ? 1 : 0;
  if (sr.relocalised) {
    ++relocalisations;
    last_relocalisation_frame = frame;
    last_relocalisation_inliers = sr.relocalisation_inliers;
  }
  ++frames;
  if (sr.mono) {
    // A pose from bearings of the map (camera loss): not an odometry failure.
  } else if (sr.relocalised && !r.tracked) {
    // No frame-to-frame motion (after a loss), the pose found against a kept keyframe.
    ++relocalised_untracked;
  } else if (sr.stereo_resumed && !r.tracked) {
    // The first stereo frame after mono ones: the odometry's previous frame is stale; the pose
    // comes from the filter's prediction and the landmark observations.
    ++resumed_untracked;
  } else if (r.tracked) {
    ++tracked;
    if (r.inliers > 0) {  // a motion was estimated (not the first frame)
      sum_motion_m2 += r.motion_rms_mahalanobis * r.motion_rms_mahalanobis;
      ++motion_frames;
      if (r.disparity_offset_frame.used) ++disparity_offset_frames;
    }
  } else {
    ++failure_counts[r.failure];
    if (failures.size() < 100) failures.emplace_back(frame, r.failure);
  }
  disparity_offset_px = r.disparity_offset_px;
  sum_corners += r.corners;
  sum_points += r.stereo_points;
  sum_matches += r.temporal_matches;
  sum_inliers += r.inliers;
  repredicted += r.repredicted ? 1 : 0;
  retried += r.retried ? 1 : 0;
  sum_recovered += r.stereo_stats.recovered;
  sum_continuity_rejected += r.stereo_stats.continuity_rejected;
}

namespace {
std::string latency(const rt::LatencySummary& l) {
  JsonObject j;
  j.add("p50_ms", l.p50_ms, 3).add("p99_ms", l.p99_ms, 3).add("max_ms", l.max_ms, 3);
  j.add("count", static_cast<std::int64_t>(l.count));
  return j.str();
}
}  // namespace

std::string statsJson(const config::RunConfig& cfg, const std::string& source, const RunSummary& s,
                      EstimatorOutputs outputs, const StageTimes& times,
                      const rt::PipelineReport& pipeline, const std::string& error,
                      const std::string& map_json, const std::string& loop_json) {
  JsonObject fails;
  for (const auto& [reason, n] : s.failure_counts) fails.add(reason, n);
  std::string list = "[";
  for (std::size_t i = 0; i < s.failures.size(); ++i) {
    JsonObject f;
    f.add("frame", s.failures[i].first).add("reason", s.failures[i].second);
    list += (i ? ", " : "") + f.str();
  }
  list += "]";
  const double n = std::max(1, s.frames);
  JsonObject j;
  j.add("source", source)
      .add("mode", config::toString(cfg.mode))
      .add("frames", s.frames)
      .add("frames_tracked", s.tracked)
      .add("frames_without_pose",
           s.frames - s.tracked - s.mono_frames - s.resumed_untracked - s.relocalised_untracked)
      // Camera loss: frames posed from the left image alone (bearings of the map), the times
      // the right camera became unusable and why, frame by frame
      .add("frames_monocular", s.mono_frames)
      .add("frames_mono_initializing", s.mono_initializing)
      .add("mono_scale_from_altitude_frame", s.altitude_scaled_frame)
      .add("altitude_readings", s.altitude_readings)
      .add("altitude_readings_rejected", s.altitude_rejected)
      .add("right_camera_losses", s.right_camera_losses)
      .add("frames_stereo_resumed_untracked", s.resumed_untracked)
      .add("frames_lost", s.frames_lost)
      .add("relocalisations", s.relocalisations)
      .add("relocalisation_failures", s.relocalisation_failures)
      .add("last_relocalisation_frame", s.last_relocalisation_frame)
      .add("last_relocalisation_inliers", s.last_relocalisation_inliers)
      .add("right_camera_missing_frames", s.right_camera_state_counts[1])
      .add("right_camera_flat_frames", s.right_camera_state_counts[2])
      .add("right_camera_frozen_frames", s.right_camera_state_counts[3])
      .add("source_frames_skipped", s.source_frames_skipped)
      .addRaw("without_pose_reasons", fails.str())
      .addRaw("without_pose_frames", list)
      .add("mean_corners", s.sum_corners / n, 1)
      .add("mean_stereo_points", s.sum_points / n, 1)
      .add("mean_stereo_continuity_rejected", s.sum_continuity_rejected / n, 1)
      .add("mean_stereo_recovered", s.sum_recovered / n, 1)
      .add("mean_temporal_matches", s.sum_matches / n, 1)
      .add("mean_motion_inliers", s.sum_inliers / n, 1)
      .add("frames_repredicted", s.repredicted)
      .add("frames_retried", s.retried)
      // Mean over the estimated motions of the inliers' squared Mahalanobis residual per
      // dof: 1 when the 3D point covariances fit the data (a little less after the outlier loop)
      .add("motion_residual_per_dof",
           s.motion_frames > 0 ? s.sum_motion_m2 / (3.0 * static_cast<double>(s.motion_frames))
                               : 0.0,
           3)
      // Online disparity offset (src/motion/disparity_offset.hpp): the estimate after the last
      // frame and the frames it was estimated from
      .add("disparity_offset_px", s.disparity_offset_px, 4)
      .add("disparity_offset_frames", s.disparity_offset_frames)
      .add("threads", cfg.threads)
      .add("dense_stereo", cfg.odometry.dense)
      .add("seed", static_cast<std::int64_t>(cfg.seed))
      .add("front_end_median_ms", times.median("front_end"), 3);
  if (outputs.landmark_map) {
    j.add("landmarks_in_state_mean", s.sum_in_state / n, 1)
        .add("landmarks_in_state_max", s.max_in_state)
        .add("landmarks_in_map", s.landmarks_in_map)
        .add("landmarks_added", s.added)
        .add("landmarks_retired", s.retired)
        .add("landmarks_restored", s.restored)
        .add("mean_landmarks_observed", s.sum_observed / n, 1)
        .add("mean_landmarks_reperceived", s.sum_reperceived / n, 2)
        .add("mean_observations_gated", s.sum_gated / n, 2)
        // 1 when the observation noise and the state covariance match the innovations
        .add("observation_nis_per_dof",
             s.nis_count > 0 ? s.sum_nis / (3.0 * static_cast<double>(s.nis_count)) : 0.0, 3)
        .add("mean_landmarks_predicted_visible", s.sum_visible / n, 1)
        .add("mean_landmark_search_no_match", s.sum_no_match / n, 2)
        .add("mean_landmark_search_no_stereo", s.sum_no_stereo / n, 2)
        // Camera loss: landmarks initialised from bearings (seed 003), bearings accepted and
        // their d^2 per dof (2 dof each)
        .add("landmarks_added_from_bearings", s.bearing_added)
        .add("bearing_observations", s.bearing_count)
        .add("bearing_nis_per_dof",
             s.bearing_count > 0 ? s.sum_bearing_nis / (2.0 * static_cast<double>(s.bearing_count))
                                 : 0.0,
             3)
        .add("ekf_median_ms", times.median("ekf"), 3);
  }
  if (s.source_frames_skipped > 0) j.add("source_skipped_frames", s.source_frames_skipped_detail);
  if (!s.source_counters.empty()) {
    JsonObject c;
    for (const auto& [name, value] : s.source_counters) c.add(name, value);
    j.addRaw("source_counters", c.str());
  }
  j.addRaw("stage_ms", times.json());
  JsonObject p;
  p.add("threaded", !cfg.pipeline.runner.sequential)
      .add("rate_hz", cfg.pipeline.runner.rate_hz, 3)
      .add("frames_captured", static_cast<std::int64_t>(pipeline.captured))
      .add("frames_published", static_cast<std::int64_t>(pipeline.published))
      .add("frames_dropped", static_cast<std::int64_t>(pipeline.dropped))
      .add("wall_s", pipeline.wall_s, 3)
      .add("fps", pipeline.fps, 2)
      .addRaw("capture", latency(pipeline.stage("capture")))
      .addRaw("stereo", latency(pipeline.stage("stereo")))
      .addRaw("estimator", latency(pipeline.stage("estimator")))
      .addRaw("publisher", latency(pipeline.stage("publisher")))
      .addRaw("end_to_end", latency(pipeline.end_to_end));
  std::string queues = "[";
  for (std::size_t i = 0; i < pipeline.edges.size(); ++i) {
    const rt::EdgeReport& e = pipeline.edges[i];
    JsonObject q;
    q.add("name", e.name).add("capacity", e.capacity).add("max_depth", e.max_depth);
    q.add("drops", static_cast<std::int64_t>(e.drops));
    queues += (i ? ", " : "") + q.str();
  }
  queues += "]";
  p.addRaw("queues", queues);
  j.addRaw("pipeline", p.str());
  {  // stage stalls: a stage working on one frame for longer than service.stall_timeout_s
    std::string stages = "[";
    const rt::HealthSnapshot& h = pipeline.health;
    for (std::size_t i = 0; i < h.stalls.size(); ++i) {
      JsonObject st;
      st.add("stage", h.stalls[i].stage)
          .add("count", h.stalls[i].count)
          .add("longest_ms", h.stalls[i].longest_ms, 1);
      stages += (i ? ", " : "") + st.str();
    }
    JsonObject sj;
    sj.add("timeout_s", cfg.service.stall_timeout_s, 3)
        .add("count", h.totalStalls())
        .addRaw("stages", stages + "]");
    j.addRaw("stalls", sj.str());
  }
  if (!map_json.empty()) j.addRaw("map", map_json);
  if (!loop_json.empty()) j.addRaw("loop", loop_json);
  if (s.lcm_commands) {
    const drivers::CommandCounts& c = *s.lcm_commands;
    JsonObject refused;
    for (int k = 0; k < drivers::kNumCommandRefusals; ++k)
      refused.add(drivers::refusalName(static_cast<drivers::CommandRefusal>(k)), c.refused[k]);
    JsonObject cj;
    cj.add("enabled", cfg.lcm.commands.enabled)
        .add("accepted", c.accepted)
        .add("refused", c.refusedTotal())
        .addRaw("refused_by_reason", refused.str());
    j.addRaw("lcm_commands", cj.str());
  }
  if (!error.empty()) j.add("error", error);
  return j.str() + "\n";
}

}  // namespace svslam::run
