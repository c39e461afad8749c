// The map: section of `svslam run`'s configuration: values land in RunConfig::dem,
// map_enabled, map_geo_origin, map_publish_period_s (and pipeline.scheduling.mapper,
// lcm.map_tile_channel); every bad entry is rejected with a message naming its key.
#include <gtest/gtest.h>

#include <string>

#include "pipeline/config/run_config.hpp"

using svslam::config::parseRunConfig;
using svslam::config::RunConfig;

namespace {

std::string errorOf(const std::string& yaml) {
  RunConfig c;
  const svslam::Status s = parseRunConfig(yaml, "test.yaml", c);
  return s ? "" : s.message();
}

}  // namespace

TEST(MapConfig, DefaultsAreTheDemParamsDefaults) {
  RunConfig c;
  ASSERT_TRUE(parseRunConfig("", "empty.yaml", c));
  const svslam::map::DemParams d;
  EXPECT_TRUE(c.map_enabled);
  EXPECT_EQ(c.dem.cell_m, d.cell_m);
  EXPECT_EQ(c.dem.gravity_in_first_camera, d.gravity_in_first_camera);
  EXPECT_EQ(c.dem.tile_cells, d.tile_cells);
  EXPECT_EQ(c.dem.max_tiles, d.max_tiles);
  EXPECT_FALSE(c.map_geo_origin.has_value());
  EXPECT_EQ(c.map_publish_period_s, 1.0);
  EXPECT_EQ(c.lcm.params.map_tile_channel, "SVSLAM_MAP_TILE");
  EXPECT_TRUE(c.pipeline.mapper.cpus.empty());
}

TEST(MapConfig, GoodFileParses) {
  RunConfig c;
  const svslam::Status s = parseRunConfig(
      "map:\n"
      "  enabled: false\n"
      "  cell_m: 0.25\n"
      "  gravity_in_first_camera: [0, 0.9, 0.1]\n"
      "  tile_cells: 32\n"
      "  max_range_m: 40.0\n"
      "  min_disparity_px: 2.5\n"
      "  gate_chi2: 16\n"
      "  min_sigma_m: 0.02\n"
      "  max_tiles: 100\n"
      "  geo_origin: [43.6, 1.45, 150.0]\n"
      "  publish_period_s: 0.5\n"
      "pipeline: {scheduling: {mapper: {cpus: [1], fifo_priority: 5}}}\n"
      "lcm: {map_tile_channel: TILES}\n",
      "good.yaml", c);
  ASSERT_TRUE(s) << s.message();
  EXPECT_FALSE(c.map_enabled);
  EXPECT_EQ(c.dem.cell_m, 0.25);
  EXPECT_EQ(c.dem.gravity_in_first_camera, (std::array<double, 3>{0.0, 0.9, 0.1}));
  EXPECT_EQ(c.dem.tile_cells, 32);
  EXPECT_EQ(c.dem.max_range_m, 40.0);
  EXPECT_EQ(c.dem.min_disparity_px, 2.5);
  EXPECT_EQ(c.dem.gate_chi2, 16.0);
  EXPECT_EQ(c.dem.min_sigma_m, 0.02);
  EXPECT_EQ(c.dem.max_tiles, 100);
  ASSERT_TRUE(c.map_geo_origin.has_value());
  EXPECT_EQ(*c.map_geo_origin, (std::array<double, 3>{43.6, 1.45, 150.0}));
  EXPECT_EQ(c.map_publish_period_s, 0.5);
  EXPECT_EQ(c.pipeline.mapper.cpus, std::vector<int>{1});
  EXPECT_EQ(c.pipeline.mapper.fifo_priority, 5);
  EXPECT_EQ(c.lcm.params.map_tile_channel, "TILES");

  RunConfig e;  // [] = no geo origin
  ASSERT_TRUE(parseRunConfig("map: {geo_origin: []}\n", "e.yaml", e));
  EXPECT_FALSE(e.map_geo_origin.has_value());
}

TEST(MapConfig, BadEntriesAreNamed) {
  auto names = [](const std::string& yaml, const std::string& key) {
    const std::string e = errorOf(yaml);
    EXPECT_NE(e.find(key), std::string::npos) << yaml << " -> '" << e << "'";
  };
  names("map: {cel_m: 0.1}\n", "'map.cel_m'");
  names("map: {cell_m: 0}\n", "'map.cell_m'");
  names("map: {cell_m: 500}\n", "'map.cell_m'");
  names("map: {cell_m: 0.001}\n", "map.cell_m");  // in the key's range, not in (0.001, 100]
  names("map: {cell_m: .nan}\n", "'map.cell_m'");
  names("map: {gravity_in_first_camera: [0, 1]}\n", "'map.gravity_in_first_camera'");
  names("map: {gravity_in_first_camera: [0, .nan, 1]}\n", "'map.gravity_in_first_camera'");
  names("map: {gravity_in_first_camera: [0, 0, 0]}\n", "map.gravity_in_first_camera");
  names("map: {gravity_in_first_camera: [2, 0, 0]}\n", "map.gravity_in_first_camera");
  names("map: {gravity_in_first_camera: 1}\n", "'map.gravity_in_first_camera'");
  names("map: {tile_cells: 4}\n", "'map.tile_cells'");
  names("map: {max_range_m: -1}\n", "'map.max_range_m'");
  names("map: {min_disparity_px: 0}\n", "'map.min_disparity_px'");
  names("map: {gate_chi2: 0}\n", "'map.gate_chi2'");
  names("map: {min_sigma_m: -0.1}\n", "'map.min_sigma_m'");
  names("map: {max_tiles: 0}\n", "'map.max_tiles'");
  names("map: {enabled: maybe}\n", "'map.enabled'");
  names("map: {geo_origin: [43.6, 1.45]}\n", "'map.geo_origin'");
  names("map: {geo_origin: [85, 0, 0]}\n", "'map.geo_origin'");
  names("map: {geo_origin: [0, 181, 0]}\n", "'map.geo_origin'");
  names("map: {geo_origin: [0, .inf, 0]}\n", "'map.geo_origin'");
  names("map: {publish_period_s: 0}\n", "'map.publish_period_s'");
  names("map: {publish_period_s: 4000}\n", "'map.publish_period_s'");
  names("pipeline: {scheduling: {mapper: {fifo_priority: 100}}}\n",
        "'pipeline.scheduling.mapper.fifo_priority'");
  names("lcm: {map_tile_channel: 'a b'}\n", "a b");
}
