#pragma once
// Ground truth of the elevation map (seed 001 sec 5.2) for the synthetic flight: the exact
// terrain height of every cell of a window of the map, with how often stereo saw it.
//
// Frames. The map frame (src/map/map_frame.hpp) has its origin at the first left camera centre
// c0 (world coordinates of the flight, z up) and R_map_world maps the first camera's frame into
// it, so R_W_map = R_W_C0 R_map_world^T and a map point p is the world point c0 + R_W_map p.
// When R_map_world comes from the source's exact gravity (gravityInFirstCamera), R_W_map's third
// column is (0, 0, 1): map z is world z, and the map point (x, y, h) above the cell centre
// (x, y) lies at the horizontal world position (X, Y) = c0_xy + R_W_map[0:2, 0:2] (x, y)
// whatever h, so the cell's true height is h = heightAt(X, Y) - c0.z exactly.
//
// Visibility. The terrain point P = (X, Y, heightAt(X, Y)) of a cell is "seen" by frame k when it
// projects inside the left image of the true pose k: depth z > 0, |P - camera| <= max_range_m
// (farther ground renders as sky) and the pinhole projection (f, cx, cy) within
// [-0.5, width - 0.5) x [-0.5, height - 0.5) (the pixel areas). Occlusion by relief is not
// tested (none for a camera looking down). It is in stereo overlap when it also projects inside
// the right image (the left camera translated by baseline_m along its x axis).
#include <Eigen/Core>

#include "core/status.hpp"
#include "drivers/synthetic/synthetic_flight.hpp"
#include "map/dem_raster.hpp"

namespace svslam::drivers {

// Fills the window already set in `raster` (cell_m finite and > 0, i0, j0, cols, rows >= 1;
// the arrays are resized to rows x cols): for each cell whose terrain point is seen by at least
// one of frames 0 .. frames - 1 (1 <= frames <= flight.size()), height_m = its true height in
// the map frame, sigma_m = 0, count = the number of those frames that see it in both images;
// NaN height and sigma, count 0 elsewhere; luminance 0 everywhere. Error when the window or
// frames is out of range, or when R_map_world is not a rotation whose z axis is the world's
// vertical (within 1e-9).
Status syntheticGroundTruthDem(const SyntheticFlight& flight, int frames,
                               const Eigen::Matrix3d& R_map_world, map::DemRaster& raster);

}  // namespace svslam::drivers
