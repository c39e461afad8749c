#pragma once
// The mapper stage of `svslam run` (seed 001 sec 5.2): after each pose is published, the frame's
// dense disparity is fused into the elevation map (src/map/dem_fuser.hpp) with the estimated
// pose and covariance. It runs on its own thread after publication (StageSpec::after_publish):
// live and paced, a frame it is too busy for is skipped and counted, never delaying a pose; as
// fast as possible, it takes every frame (same map threaded or sequential).
//
// Outputs, written atomically at the end of the run (also after SIGTERM) and on the save_map
// command: dem.tif (height, height sigma, count), ortho.tif, ortho.png, dem_hillshade.png, and
// with a source that knows its terrain (synthetic) groundtruth_dem.tif on the same grid. On LCM,
// every map.publish_period_s, each tile changed since the last period as a map_tile_t.
// With loop closing (loop.enabled) every cell remembers the latest frame that wrote into it, and
// after the run, when loops were closed, writeReplaced() re-places the map with the corrected
// trajectory (src/map/dem_replacer.hpp): dem_optimized.tif, ortho_optimized.tif and
// ortho_optimized.png beside the online map.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include "core/status.hpp"
#include "drivers/files/dem_files.hpp"
#include "drivers/lcm/lcm_transport.hpp"
#include "drivers/source/stereo_source.hpp"
#include "map/dem_fuser.hpp"
#include "map/dem_map.hpp"
#include "pipeline/config/run_config.hpp"
#include "pipeline/realtime/frame_slot.hpp"
#include "pipeline/run/run_outputs.hpp"

namespace svslam::rt {

class MapStage {
 public:
  // `source` and `lcm` (may be null) outlive this object.
  MapStage(const config::RunConfig& cfg, drivers::StereoSource& source, std::string out_dir,
           drivers::LcmLink* lcm);
  // Gravity (the source's when it knows it, else map.gravity_in_first_camera), the map frame,
  // the fuser. `pose_covariance`: the estimator's covariance is a pose covariance (ekf); else
  // (vo) the map's sigmas are those of dense stereo alone.
  Status init(bool pose_covariance);
  // Mapper thread: fuses one published frame.
  Status process(FrameSlot& slot);
  // Any thread: write the map files into `dir` after the next frame (or at finish()); the
  // answer on LCM carries `command_seq` and `prefix` (what the caller already did).
  void requestSave(const std::string& dir, std::int64_t command_seq, const std::string& prefix);
  // After the run: writes the map files into the output folder (and answers a pending save).
  Status finish();
  // After finish() and loop closing's finish: the map re-placed, each fused frame f moved by
  // correction(f, M) (T_corrected = M T_online; false for every frame: nothing is written).
  Status writeReplaced(const std::function<bool(std::int64_t, Eigen::Isometry3d&)>& correction);
  // Mapper thread, during the run (after a loop-closing solution): the map re-placed with
  // `correction` as writeReplaced does; on LCM every tile of it goes to
  // lcm.map_tile_optimized_channel, with an empty tile (no data) for each tile of the previous
  // re-placed map it no longer has; save_map then also writes it (dem_optimized.tif, ...).
  // Costs one pass over the map's cells (stats.json map.replaced.ms).
  Status replaceLive(const std::function<bool(std::int64_t, Eigen::Isometry3d&)>& correction,
                     std::int64_t t_ns);
  // stats.json's "map" object; `skipped_busy`: frames the runner skipped for this stage.
  std::string json(std::int64_t skipped_busy) const;
  const map::DemMap& map() const { return *map_; }
  const run::StageTimes& times() const { return times_; }
  const Eigen::Matrix3d& R_map_world() const { return R_map_world_; }

 private:
  Status writeFiles(const std::string& dir);
  // The map re-placed with `correction` into `out` (`any`: some frame had a correction; else
  // `out` is left empty); sets replaced_json_.
  Status replace(const std::function<bool(std::int64_t, Eigen::Isometry3d&)>& correction,
                 map::DemMap& out, bool& any);
  map::DemParams replacedParams() const;
  Status writeReplacedFiles(const map::DemMap& replaced, const std::string& dir) const;
  // map.geo_origin in `storage`, or null without one.
  const drivers::GeoOrigin* geoOrigin(drivers::GeoOrigin& storage) const;
  void applySave(std::int64_t t_ns);
  void publishTiles(std::int64_t t_ns);
  // Encodes tile_raster_ as tile (ti, tj) and publishes it on `channel`; counts it in
  // `published` (also its message seq) when sent.
  void sendTile(const std::string& channel, int ti, int tj, std::int64_t t_ns,
                std::int64_t& published);

  config::RunConfig cfg_;
  drivers::StereoSource& source_;
  std::string out_dir_;
  drivers::LcmLink* lcm_;
  bool pose_covariance_ = false;
  Eigen::Matrix3d R_map_world_ = Eigen::Matrix3d::Identity();
  std::string gravity_from_;  // "source" or "config"
  std::unique_ptr<map::DemMap> map_;
  std::unique_ptr<map::DemFuser> fuser_;
  map::DemRaster tile_raster_;  // one tile, reused for LCM
  std::vector<std::uint8_t> tile_bytes_;
  std::int64_t published_seq_ = -1;  // tiles with last_seq above this are sent next period
  std::int64_t next_publish_ns_ = 0;
  std::int64_t tiles_published_ = 0;
  // Counters (mapper thread; read after the run).
  std::int64_t frames_fused_ = 0;
  int frames_seen_ = 0;  // source frames 0 .. frames_seen_ - 1 reached the mapper (ground truth)
  std::map<std::string, std::int64_t> not_fused_;  // reason -> frames
  struct Totals {
    std::int64_t fused = 0, gated = 0, not_finite = 0, out_of_range = 0, no_tile = 0;
  } totals_;  // points
  run::StageTimes times_;
  std::vector<std::int64_t> fused_frames_;  // source frame of each fusion (by sequence number)
  std::string replaced_json_;               // stats.json's map.replaced, the last re-placement
  // Live re-placement (replaceLive): the last re-placed map (save_map writes it; mapper thread
  // only, like applySave, or after the run), the tiles it sent on LCM, counters.
  std::unique_ptr<map::DemMap> replaced_;
  std::set<std::pair<int, int>> replaced_tiles_sent_;
  std::int64_t live_replacements_ = 0;
  std::int64_t replaced_tiles_published_ = 0;
  // Pending save_map.
  std::mutex save_mutex_;
  std::string save_dir_, save_prefix_;
  std::int64_t save_seq_ = -1;
};

}  // namespace svslam::rt
