// The keys of the map section (the elevation map: RunConfig::map_enabled, dem, map_geo_origin,
// map_publish_period_s): field, unit, range and doc of each, once.
#include "map/map_frame.hpp"
#include "pipeline/config/config_keys.hpp"

namespace svslam::config {
namespace {

std::string flowList(const double* v, std::size_t n) {
  std::string s = "[";
  for (std::size_t i = 0; i < n; ++i) s += (i ? ", " : "") + formatValue(v[i]);
  return s + "]";
}

Status keyError(const ConfigReader& r, const std::string& key, const std::string& what) {
  return Status::invalidArgument(r.name() + ": key '" + key + "' " + what);
}

// map.gravity_in_first_camera: 3 finite numbers, non-zero, not along the camera x axis.
ConfigKey gravityKey() {
  ConfigKey k{"gravity_in_first_camera",
              "",
              "3 numbers",
              "gravity direction in the first left camera frame (x right, y down, z forward); "
              "[0, 0, 1]: looking straight down (blimp), [0, 1, 0]: level, forward (car)",
              {},
              {}};
  k.read = [](ConfigReader& r, const std::string& key, RunConfig& c) {
    auto& g = c.dem.gravity_in_first_camera;
    std::vector<double> list(g.begin(), g.end());
    SVSLAM_TRY(r.read(key, list));
    if (list.size() != 3)
      return keyError(r, key, "must hold 3 numbers (got " + std::to_string(list.size()) + ")");
    const std::array<double, 3> v{list[0], list[1], list[2]};
    Eigen::Matrix3d R_map_world;
    if (Status s = map::mapRotationFromGravity(v, R_map_world); !s)
      return Status::invalidArgument(r.name() + ": " + s.message());
    g = v;
    return Status::ok();
  };
  k.value = [](const RunConfig& c) { return flowList(c.dem.gravity_in_first_camera.data(), 3); };
  return k;
}

// map.geo_origin: [] or [lat_deg, lon_deg, alt_m].
ConfigKey geoOriginKey() {
  ConfigKey k{"geo_origin",
              "",
              "none or 3 numbers",
              "[lat_deg, lon_deg, alt_m]: WGS84 position of the map origin (lat -80..84, "
              "lon -180..180, ellipsoidal altitude) for georeferenced outputs; [] = none",
              {},
              {}};
  k.read = [](ConfigReader& r, const std::string& key, RunConfig& c) {
    std::vector<double> list;
    if (c.map_geo_origin) list.assign(c.map_geo_origin->begin(), c.map_geo_origin->end());
    SVSLAM_TRY(r.read(key, list));
    if (list.empty()) {
      c.map_geo_origin.reset();
      return Status::ok();
    }
    if (list.size() != 3)
      return keyError(r, key,
                      "must be [] or [lat_deg, lon_deg, alt_m] (got " +
                          std::to_string(list.size()) + " numbers)");
    if (list[0] < -80.0 || list[0] > 84.0)
      return keyError(r, key, "latitude must be in [-80, 84] deg");
    if (list[1] < -180.0 || list[1] > 180.0)
      return keyError(r, key, "longitude must be in [-180, 180] deg");
    if (list[2] < -1e4 || list[2] > 1e5)
      return keyError(r, key, "altitude must be in [-10000, 100000] m");
    c.map_geo_origin = std::array<double, 3>{list[0], list[1], list[2]};
    return Status::ok();
  };
  k.value = [](const RunConfig& c) {
    return c.map_geo_origin ? flowList(c.map_geo_origin->data(), 3) : std::string("[]");
  };
  return k;
}

}  // namespace

ConfigSection mapConfigSection() {
  ConfigSection s{"map", "elevation map: DEM + orthoimage (src/map/dem_params.hpp)", {}};
  s.keys = {
      flag("enabled", SVSLAM_FIELD(map_enabled), "true: the mapper stage fuses dense stereo"),
      number("cell_m", SVSLAM_FIELD(dem.cell_m), 0.001, 100, "m",
             "grid cell side, > 0.001 (map frame: origin the first left camera centre, z up)"),
      gravityKey(),
      number("tile_cells", SVSLAM_FIELD(dem.tile_cells), 8, 1024, "",
             "tile side in cells (tiles are allocated on demand)"),
      number("max_range_m", SVSLAM_FIELD(dem.max_range_m), 0.01, 1e6, "m",
             "points farther from the camera are not fused"),
      number("min_disparity_px", SVSLAM_FIELD(dem.min_disparity_px), 0.01, 1024, "px",
             "smaller disparities (far, imprecise) are not fused"),
      number("gate_chi2", SVSLAM_FIELD(dem.gate_chi2), 1e-6, 1e6, "",
             "Mahalanobis gate (chi-square 1 dof) of a point's height against its cell; "
             "beyond, the point's variance is inflated onto the gate"),
      number("reject_variance_factor", SVSLAM_FIELD(dem.reject_variance_factor), 1, 1e3, "",
             "a cell whose estimate most of a frame's points reject has its variance "
             "multiplied by this before the frame is fused (moved objects fade; 1 = off)"),
      number("max_height_above_camera_m", SVSLAM_FIELD(dem.max_height_above_camera_m), -1e6, 1e6,
             "m",
             "points higher than this above the camera centre are not fused (a car: 0.5, "
             "below street lamps and branches)"),
      number("min_sigma_m", SVSLAM_FIELD(dem.min_sigma_m), 0, 100, "m",
             "floor of every cell's height standard deviation (model error of dense stereo)"),
      number("max_tiles", SVSLAM_FIELD(dem.max_tiles), 1, 1000000, "",
             "bound on the tiles in memory (64 x 64 cells x 12 B = 48 KiB each)"),
      number("max_raster_mcells", SVSLAM_FIELD(dem.max_raster_mcells), 1, 4096, "",
             "bound on the written map raster (bounding box of the tiles), millions of cells "
             "(13 B each); a larger map is not written, with an error"),
      geoOriginKey(),
      number("publish_period_s", SVSLAM_FIELD(map_publish_period_s), 0.01, 3600, "s",
             "tiles changed since the last period go to lcm.map_tile_channel every this many s"),
      number("replace_period_s", SVSLAM_FIELD(map_replace_period_s), 0, 86400, "s",
             "with loop closing: after a new solution the map is re-placed during the flight "
             "(lcm.map_tile_optimized_channel, save_map) at most every this many s; 0 = at the "
             "end of the run only"),
  };
  return s;
}

}  // namespace svslam::config
