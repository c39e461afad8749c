// Ground-truth elevation map of the synthetic flight (synthetic_dem.hpp).
#include "drivers/synthetic/synthetic_dem.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace svslam::drivers {
namespace {

constexpr long long kMaxCells = 50'000'000;  // bound on the window, cells

// Bounding box (map x, y) of the terrain slab zmin <= Z <= zmax (world) inside the left
// camera's view pyramid truncated at depth `depth_m`: the vertices of their intersection are
// the pyramid's vertices inside the slab and the crossings of its edges with the slab's planes.
bool footprintBox(const Eigen::Isometry3d& T_W_C, const StereoCalibration& cal, double depth_m,
                  double zmin, double zmax, const Eigen::Matrix3d& R_map_W,
                  const Eigen::Vector3d& c0, Eigen::Vector2d& lo, Eigen::Vector2d& hi) {
  const Eigen::Vector3d apex = T_W_C.translation();
  std::array<Eigen::Vector3d, 4> far;
  const double us[2] = {-0.5, cal.width - 0.5}, vs[2] = {-0.5, cal.height - 0.5};
  for (int k = 0; k < 4; ++k) {
    const double u = us[k == 1 || k == 2], v = vs[k >= 2];  // corners in order around the image
    const Eigen::Vector3d ray((u - cal.cx_px) / cal.f_px, (v - cal.cy_px) / cal.f_px, 1.0);
    far[static_cast<std::size_t>(k)] = T_W_C * (depth_m * ray);
  }
  std::vector<Eigen::Vector3d> pts;
  auto addVertex = [&](const Eigen::Vector3d& p) {
    if (p.z() >= zmin && p.z() <= zmax) pts.push_back(p);
  };
  auto addEdge = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    for (double z0 : {zmin, zmax}) {
      if (a.z() == b.z() || (a.z() - z0) * (b.z() - z0) > 0.0) continue;
      pts.push_back(a + (z0 - a.z()) / (b.z() - a.z()) * (b - a));
    }
  };
  addVertex(apex);
  for (std::size_t k = 0; k < 4; ++k) {
    addVertex(far[k]);
    addEdge(apex, far[k]);
    addEdge(far[k], far[(k + 1) % 4]);
  }
  if (pts.empty()) return false;
  lo.setConstant(INFINITY);
  hi.setConstant(-INFINITY);
  for (const Eigen::Vector3d& p : pts) {
    const Eigen::Vector2d m = (R_map_W * (p - c0)).head<2>();
    lo = lo.cwiseMin(m);
    hi = hi.cwiseMax(m);
  }
  return true;
}

// Indices [first, last] of the cells whose centre (k + 0.5) cell_m lies in [a, b], clipped to
// [k0, k0 + n - 1]; first > last when none.
void cellRange(double a, double b, double cell_m, int k0, int n, int& first, int& last) {
  const double f = std::ceil(a / cell_m - 0.5), l = std::floor(b / cell_m - 0.5);
  first = static_cast<int>(std::clamp(f, static_cast<double>(k0), static_cast<double>(k0) + n));
  last =
      static_cast<int>(std::clamp(l, static_cast<double>(k0) - 1, static_cast<double>(k0) + n - 1));
}

}  // namespace

Status syntheticGroundTruthDem(const SyntheticFlight& flight, int frames,
                               const Eigen::Matrix3d& R_map_world, map::DemRaster& raster) {
  auto bad = [](const std::string& m) {
    return Status::invalidArgument("syntheticGroundTruthDem: " + m);
  };
  if (frames < 1 || frames > flight.size())
    return bad("frames must be in [1, " + std::to_string(flight.size()) + "]");
  if (!(std::isfinite(raster.cell_m) && raster.cell_m > 0.0))
    return bad("raster cell_m must be finite and > 0");
  if (raster.cols < 1 || raster.rows < 1 ||
      static_cast<long long>(raster.cols) * raster.rows > kMaxCells)
    return bad("raster window must have 1 to " + std::to_string(kMaxCells) + " cells");
  if (static_cast<long long>(raster.i0) + raster.cols > INT32_MAX ||
      static_cast<long long>(raster.j0) + raster.rows > INT32_MAX)
    return bad("raster window overflows the map's int indices");
  if (!R_map_world.allFinite() ||
      (R_map_world * R_map_world.transpose() - Eigen::Matrix3d::Identity()).norm() > 1e-9 ||
      R_map_world.determinant() < 0.0)
    return bad("R_map_world is not a rotation");

  const Eigen::Isometry3d T_W_C0 = flight.pose(0);
  const Eigen::Vector3d c0 = T_W_C0.translation();
  const Eigen::Matrix3d R_W_map = T_W_C0.linear() * R_map_world.transpose();
  if ((R_W_map.col(2) - Eigen::Vector3d::UnitZ()).norm() > 1e-9)
    return bad(
        "the map z axis is not the world's vertical (R_map_world must come from the "
        "source's gravity)");
  const Eigen::Matrix3d R_map_W = R_W_map.transpose();

  const int cols = raster.cols, rows = raster.rows;
  raster.resize(cols, rows);
  const double cell = raster.cell_m;
  const std::size_t n = static_cast<std::size_t>(cols) * static_cast<std::size_t>(rows);
  // Terrain point of every cell, world coordinates.
  std::vector<Eigen::Vector3d> P(n);
  for (int r = 0; r < rows; ++r) {
    const double y = (raster.j0 + rows - 1 - r + 0.5) * cell;
    for (int c = 0; c < cols; ++c) {
      const double x = (raster.i0 + c + 0.5) * cell;
      const Eigen::Vector2d XY =
          c0.head<2>() + R_W_map.topLeftCorner<2, 2>() * Eigen::Vector2d(x, y);
      P[raster.index(c, r)] = Eigen::Vector3d(XY.x(), XY.y(), flight.heightAt(XY.x(), XY.y()));
    }
  }

  const StereoCalibration& cal = flight.calibration();
  const double range_m = flight.params().max_range_m;
  const double zmax = flight.maxAbsHeight() + 1e-9, zmin = -zmax;
  const double u_lo = -0.5, u_hi = cal.width - 0.5, v_lo = -0.5, v_hi = cal.height - 0.5;
  std::vector<std::uint8_t> seen(n, 0);
  for (int k = 0; k < frames; ++k) {
    const Eigen::Isometry3d T_W_C = flight.pose(k);
    Eigen::Vector2d lo, hi;
    if (!footprintBox(T_W_C, cal, range_m, zmin, zmax, R_map_W, c0, lo, hi)) continue;
    int i_first, i_last, j_first, j_last;
    cellRange(lo.x(), hi.x(), cell, raster.i0, cols, i_first, i_last);
    cellRange(lo.y(), hi.y(), cell, raster.j0, rows, j_first, j_last);
    const Eigen::Matrix3d R_C_W = T_W_C.linear().transpose();
    const Eigen::Vector3d cam = T_W_C.translation();
    for (int j = j_first; j <= j_last; ++j) {
      const int r = raster.j0 + rows - 1 - j;
      for (int i = i_first; i <= i_last; ++i) {
        const std::size_t idx = raster.index(i - raster.i0, r);
        const Eigen::Vector3d d = P[idx] - cam;
        const Eigen::Vector3d p = R_C_W * d;
        if (!(p.z() > 0.0) || d.squaredNorm() > range_m * range_m) continue;
        const double inv_z = 1.0 / p.z();
        const double u = cal.f_px * p.x() * inv_z + cal.cx_px;
        const double v = cal.f_px * p.y() * inv_z + cal.cy_px;
        if (!(u >= u_lo && u < u_hi && v >= v_lo && v < v_hi)) continue;
        seen[idx] = 1;
        const double u_right = cal.f_px * (p.x() - cal.baseline_m) * inv_z + cal.cx_px;
        if (u_right >= u_lo && u_right < u_hi) raster.count[idx] += 1.0f;
      }
    }
  }
  for (std::size_t idx = 0; idx < n; ++idx) {
    if (!seen[idx]) continue;
    raster.height_m[idx] = static_cast<float>(P[idx].z() - c0.z());
    raster.sigma_m[idx] = 0.0f;
  }
  return Status::ok();
}

}  // namespace svslam::drivers
