// DemParams::validate: the defaults are valid; each field out of its range is named.
#include "map/dem_params.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>
#include <utility>
#include <vector>

using svslam::map::DemParams;

TEST(DemParams, DefaultsAreValid) { EXPECT_TRUE(DemParams{}.validate()); }

TEST(DemParams, EachBadFieldIsNamed) {
  const std::vector<std::pair<std::string, std::function<void(DemParams&)>>> cases = {
      {"cell_m", [](DemParams& p) { p.cell_m = 0.001; }},
      {"cell_m", [](DemParams& p) { p.cell_m = 101.0; }},
      {"cell_m", [](DemParams& p) { p.cell_m = NAN; }},
      {"gravity_in_first_camera",
       [](DemParams& p) {
         p.gravity_in_first_camera = {0, 0, 0};
       }},
      {"gravity_in_first_camera",
       [](DemParams& p) {
         p.gravity_in_first_camera = {1, 0, 0};
       }},
      {"gravity_in_first_camera", [](DemParams& p) { p.gravity_in_first_camera[2] = NAN; }},
      {"tile_cells", [](DemParams& p) { p.tile_cells = 7; }},
      {"tile_cells", [](DemParams& p) { p.tile_cells = 1025; }},
      {"max_range_m", [](DemParams& p) { p.max_range_m = 0.0; }},
      {"max_range_m", [](DemParams& p) { p.max_range_m = INFINITY; }},
      {"min_disparity_px", [](DemParams& p) { p.min_disparity_px = -1.0; }},
      {"gate_chi2", [](DemParams& p) { p.gate_chi2 = 0.0; }},
      {"gate_chi2", [](DemParams& p) { p.gate_chi2 = 2e6; }},
      {"reject_variance_factor", [](DemParams& p) { p.reject_variance_factor = 0.5; }},
      {"reject_variance_factor", [](DemParams& p) { p.reject_variance_factor = NAN; }},
      {"min_sigma_m", [](DemParams& p) { p.min_sigma_m = -0.1; }},
      {"max_tiles", [](DemParams& p) { p.max_tiles = 0; }},
  };
  for (const auto& [field, spoil] : cases) {
    DemParams p;
    spoil(p);
    const svslam::Status s = p.validate();
    EXPECT_FALSE(s) << field;
    EXPECT_NE(s.message().find("map." + field), std::string::npos) << s.message();
  }
}
