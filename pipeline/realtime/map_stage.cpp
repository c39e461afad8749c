#include "pipeline/realtime/map_stage.hpp"

#include <algorithm>
#include <cmath>
#include <set>
#include <utility>

#include "drivers/files/dem_files.hpp"
#include "drivers/lcm/lcm_map_tile.hpp"
#include "map/dem_replacer.hpp"
#include "map/map_frame.hpp"
#include "pipeline/cli/json_writer.hpp"
#include "pipeline/realtime/pipeline_runner.hpp"
#include "pipeline/run/run_outputs.hpp"

namespace svslam::rt {

MapStage::MapStage(const config::RunConfig& cfg, drivers::StereoSource& source, std::string out_dir,
                   drivers::LcmLink* lcm)
    : cfg_(cfg), source_(source), out_dir_(std::move(out_dir)), lcm_(lcm) {}

Status MapStage::init(bool pose_covariance) {
  pose_covariance_ = pose_covariance;
  std::array<double, 3> g = cfg_.dem.gravity_in_first_camera;
  gravity_from_ = "config";
  Eigen::Vector3d g_source;
  if (source_.gravityInFirstCamera(g_source)) {
    g = {g_source.x(), g_source.y(), g_source.z()};
    gravity_from_ = "source";
  }
  if (Status s = map::mapRotationFromGravity(g, R_map_world_); !s) return s;
  map::DemParams dem = cfg_.dem;
  dem.keep_cell_sources = cfg_.loop_enabled;  // for writeReplaced
  map_ = std::make_unique<map::DemMap>(dem);
  if (Status s = map_->initStatus(); !s) return s;
  fuser_ = std::make_unique<map::DemFuser>(cfg_.dem, source_.calibration(), R_map_world_);
  return fuser_->initStatus();
}

Status MapStage::process(FrameSlot& slot) {
  const std::int64_t t0 = steadyNowNs();
  frames_seen_ = std::max(frames_seen_, slot.frame.index + 1);
  map::DemFrame in;
  in.left = slot.frame.left.cview();
  in.disparity = slot.stereo.has_disparity ? &slot.stereo.disparity : nullptr;
  in.T_world_cam = slot.result.T_world_cam;
  if (pose_covariance_) in.pose_cov = slot.result.pose_cov;
  in.t_ns = slot.frame.t_ns;
  map::DemFuseStats st;
  if (Status s = fuser_->process(in, *map_, st); !s)
    return Status(s.code(), "map, frame " + std::to_string(slot.frame.index) + ": " + s.message());
  if (st.seq >= 0 && map_->params().keep_cell_sources) {
    // Sequence numbers count up from 0 with every frame that reached the grid.
    if (st.seq != static_cast<std::int64_t>(fused_frames_.size()))
      return Status(StatusCode::kInternal, "map: fusion sequence out of step");
    fused_frames_.push_back(slot.frame.index);
  }
  if (st.skipped == map::DemSkip::kNone)
    ++frames_fused_;
  else
    ++not_fused_[map::toString(st.skipped)];
  totals_.fused += st.points_fused;
  totals_.gated += st.points_gated;
  totals_.not_finite += st.points_not_finite;
  totals_.out_of_range += st.points_out_of_range;
  totals_.no_tile += st.points_no_tile;
  times_.add("map", static_cast<double>(steadyNowNs() - t0) * 1e-6);
  if (lcm_) publishTiles(slot.frame.t_ns);
  applySave(slot.frame.t_ns);
  return Status::ok();
}

void MapStage::publishTiles(std::int64_t t_ns) {
  const std::int64_t now = steadyNowNs();
  if (now < next_publish_ns_) return;
  next_publish_ns_ = now + static_cast<std::int64_t>(cfg_.map_publish_period_s * 1e9);
  // A tile's last_seq is the fuser's number of the newest frame that wrote into it: above the
  // newest of the last period, it has changed since.
  std::int64_t newest = published_seq_;
  for (const map::DemTile& t : map_->tiles()) {
    newest = std::max(newest, t.last_seq);
    if (t.last_seq <= published_seq_) continue;
    map_->tileRaster(t, tile_raster_);
    sendTile(cfg_.lcm.params.map_tile_channel, t.ti, t.tj, t_ns, tiles_published_);
  }
  published_seq_ = newest;
}

void MapStage::sendTile(const std::string& channel, int ti, int tj, std::int64_t t_ns,
                        std::int64_t& published) {
  if (drivers::encodeMapTile(tile_raster_, ti, tj, t_ns, published, tile_bytes_) &&
      lcm_->publishRaw(channel, tile_bytes_.data(), tile_bytes_.size()))
    ++published;
}

void MapStage::requestSave(const std::string& dir, std::int64_t command_seq,
                           const std::string& prefix) {
  std::lock_guard<std::mutex> lock(save_mutex_);
  save_dir_ = dir;
  save_seq_ = command_seq;
  save_prefix_ = prefix;
}

void MapStage::applySave(std::int64_t t_ns) {
  std::string dir, prefix;
  std::int64_t seq = -1;
  {
    std::lock_guard<std::mutex> lock(save_mutex_);
    if (save_seq_ < 0) return;  // nothing pending (and nothing copied: no allocation)
    std::swap(seq, save_seq_);
    dir = save_dir_.empty() ? out_dir_ : save_dir_;
    prefix = save_prefix_;
  }
  Status ws = writeFiles(dir);
  if (ws && replaced_) ws = writeReplacedFiles(*replaced_, dir);
  if (!lcm_) return;
  drivers::CommandStatus cs;
  cs.t_ns = t_ns;
  cs.seq = seq;
  cs.command = "save_map";
  cs.ok = ws.isOk() && prefix.rfind("error", 0) != 0;
  cs.message = prefix + (ws ? "elevation map written to " + dir : ws.message());
  (void)lcm_->publishCommandStatus(cs);
}

const drivers::GeoOrigin* MapStage::geoOrigin(drivers::GeoOrigin& storage) const {
  if (!cfg_.map_geo_origin) return nullptr;
  const auto& o = *cfg_.map_geo_origin;
  storage = {o[0], o[1], o[2]};
  return &storage;
}

Status MapStage::writeFiles(const std::string& dir) {
  map::DemRaster r;
  if (Status s = map_->toRaster(r); !s) return s;
  drivers::GeoOrigin geo;
  const drivers::GeoOrigin* g = geoOrigin(geo);
  if (Status s = drivers::writeDemGeoTiff(dir + "/" + run::files::kDem, r, g); !s) return s;
  if (Status s = drivers::writeOrthoTiff(dir + "/" + run::files::kOrthoTiff, r, g); !s) return s;
  if (Status s = drivers::writeOrthoPng(dir + "/" + run::files::kOrthoPng, r); !s) return s;
  if (Status s = drivers::writeHillshadePng(dir + "/" + run::files::kHillshade, r); !s) return s;
  map::DemRaster gt = r;
  if (r.cols > 0 && source_.groundTruthDem(R_map_world_, frames_seen_, gt))
    return drivers::writeDemGeoTiff(dir + "/" + run::files::kGroundTruthDem, gt, g);
  return Status::ok();
}

Status MapStage::finish() {
  if (!map_) return Status::ok();
  std::int64_t seq = -1;
  {
    std::lock_guard<std::mutex> lock(save_mutex_);
    seq = save_seq_;
  }
  if (seq >= 0) applySave(0);  // a save_map that arrived after the last frame
  return writeFiles(out_dir_);
}

Status MapStage::replace(const std::function<bool(std::int64_t, Eigen::Isometry3d&)>& correction,
                         map::DemMap& out, bool& any) {
  any = false;
  if (!map_ || !map_->params().keep_cell_sources) return Status::ok();
  std::vector<Eigen::Isometry3d> C(fused_frames_.size(), Eigen::Isometry3d::Identity());
  for (std::size_t s = 0; s < C.size(); ++s) any = correction(fused_frames_[s], C[s]) || any;
  if (!any) return Status::ok();
  const std::int64_t t0 = steadyNowNs();
  map::DemReplacer replacer(map::DemReplacerParams{}, R_map_world_);
  map::DemReplaceStats st;
  if (Status s = replacer.process(*map_, C, out, st); !s)
    return Status(s.code(), "map re-placement: " + s.message());
  cli::JsonObject j;
  j.add("cells_in", st.cells_in)
      .add("cells_out", st.cells_out)
      .add("cells_unmoved", st.cells_no_source)
      .add("cells_no_tile", st.cells_no_tile)
      .add("max_shift_m", st.max_shift_m, 4)
      .add("rms_shift_m", st.rms_shift_m, 4)
      .add("rms_dz_m", st.rms_dz_m, 4)
      .add("ms", static_cast<double>(steadyNowNs() - t0) * 1e-6, 1);
  replaced_json_ = j.str();
  return Status::ok();
}

map::DemParams MapStage::replacedParams() const {
  map::DemParams p = map_->params();
  p.keep_cell_sources = false;
  return p;
}

Status MapStage::writeReplacedFiles(const map::DemMap& replaced, const std::string& dir) const {
  map::DemRaster r;
  if (Status s = replaced.toRaster(r); !s) return Status(s.code(), "map re-placement: " + s.message());
  drivers::GeoOrigin geo;
  const drivers::GeoOrigin* g = geoOrigin(geo);
  if (Status s = drivers::writeDemGeoTiff(dir + "/" + run::files::kDemOptimized, r, g); !s) return s;
  if (Status s = drivers::writeOrthoTiff(dir + "/" + run::files::kOrthoOptimizedTiff, r, g); !s)
    return s;
  return drivers::writeOrthoPng(dir + "/" + run::files::kOrthoOptimizedPng, r);
}

Status MapStage::writeReplaced(
    const std::function<bool(std::int64_t, Eigen::Isometry3d&)>& correction) {
  if (!map_ || !map_->params().keep_cell_sources) return Status::ok();
  map::DemMap out(replacedParams());
  bool any = false;
  if (Status s = replace(correction, out, any); !s || !any) return s;
  return writeReplacedFiles(out, out_dir_);
}

Status MapStage::replaceLive(
    const std::function<bool(std::int64_t, Eigen::Isometry3d&)>& correction, std::int64_t t_ns) {
  if (!map_ || !map_->params().keep_cell_sources) return Status::ok();
  auto out = std::make_unique<map::DemMap>(replacedParams());
  bool any = false;
  if (Status s = replace(correction, *out, any); !s || !any) return s;
  ++live_replacements_;
  if (lcm_) {
    // Every tile of the re-placed map, then an empty one (no data) for each tile of the last
    // re-placed map that this one no longer has: a listener that keeps the latest tile per
    // index holds exactly the re-placed map.
    const std::string& channel = cfg_.lcm.params.map_tile_optimized_channel;
    std::set<std::pair<int, int>> sent;
    for (const map::DemTile& t : out->tiles()) {
      out->tileRaster(t, tile_raster_);
      sendTile(channel, t.ti, t.tj, t_ns, replaced_tiles_published_);
      sent.emplace(t.ti, t.tj);
    }
    for (const auto& [ti, tj] : replaced_tiles_sent_) {
      if (sent.count({ti, tj}) != 0) continue;
      out->emptyTileRaster(ti, tj, tile_raster_);
      sendTile(channel, ti, tj, t_ns, replaced_tiles_published_);
    }
    replaced_tiles_sent_ = std::move(sent);
  }
  replaced_ = std::move(out);  // the map save_map writes as *_optimized
  return Status::ok();
}

std::string MapStage::json(std::int64_t skipped_busy) const {
  cli::JsonObject reasons;
  for (const auto& [reason, n] : not_fused_) reasons.add(reason, n);
  cli::JsonObject j;
  j.add("cell_m", cfg_.dem.cell_m, 3)
      .add("gravity_from", gravity_from_)
      .add("frames_fused", frames_fused_)
      .add("frames_skipped_busy", skipped_busy)
      .addRaw("frames_not_fused", reasons.str())
      .add("points_fused", totals_.fused)
      .add("points_gated", totals_.gated)
      .add("points_not_finite", totals_.not_finite)
      .add("points_out_of_range", totals_.out_of_range)
      .add("points_no_tile", totals_.no_tile)
      .add("tiles", map_ ? map_->numTiles() : 0)
      .add("cell_bytes", static_cast<std::int64_t>(map_ ? map_->bytes() : 0))
      .add("tiles_published", tiles_published_)
      .add("map_median_ms", times_.median("map"), 3);
  if (cfg_.loop_enabled) {
    j.add("replaced_live", live_replacements_);
    j.add("replaced_tiles_published", replaced_tiles_published_);
  }
  if (!replaced_json_.empty()) j.addRaw("replaced", replaced_json_);
  return j.str();
}

}  // namespace svslam::rt
