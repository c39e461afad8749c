// DemReplacer (dem_replacer.hpp): each cell moved with its source's correction, splatted
// bilinearly into a new grid.
#include "map/dem_replacer.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <utility>

#include "slam/ekf_checks.hpp"

namespace svslam::map {

Status DemReplacerParams::validate() const {
  if (!(min_coverage >= 0.01 && min_coverage <= 1.0))
    return Status::invalidArgument("map replacer: min_coverage must be in [0.01, 1]");
  return Status::ok();
}

DemReplacer::DemReplacer(const DemReplacerParams& params, const Eigen::Matrix3d& R_map_world)
    : params_(params), R_map_world_(R_map_world) {
  init_status_ = params.validate();
  const Eigen::Matrix3d& R = R_map_world;
  if (init_status_ &&
      !(R.allFinite() && (R.transpose() * R - Eigen::Matrix3d::Identity()).norm() < 1e-6))
    init_status_ = Status::invalidArgument("map replacer: R_map_world is not a rotation");
}

Status DemReplacer::process(const DemMap& in, const std::vector<Eigen::Isometry3d>& C_world_by_seq,
                            DemMap& out, DemReplaceStats& stats) {
  stats = DemReplaceStats{};
  if (!init_status_) return init_status_;
  if (!in.initStatus()) return in.initStatus();
  if (!out.initStatus()) return out.initStatus();
  const DemParams& p = in.params();
  if (!p.keep_cell_sources)
    return Status::failedPrecondition(
        "map replacer: the map kept no cell sources (DemParams::keep_cell_sources)");
  if (out.params().cell_m != p.cell_m || out.tileCells() != p.tile_cells)
    return Status::invalidArgument("map replacer: the two maps have different grids");
  for (std::size_t s = 0; s < C_world_by_seq.size(); ++s)
    if (Status r = ekf_checks::checkRigid(
            C_world_by_seq[s], "map replacer: correction of fusion " + std::to_string(s));
        !r)
      return r;

  // The corrections in the map frame: C_map = R C_world R^T (a rotation and a translation).
  std::vector<Eigen::Isometry3d> C_map(C_world_by_seq.size());
  for (std::size_t s = 0; s < C_map.size(); ++s) {
    C_map[s].linear() = R_map_world_ * C_world_by_seq[s].linear() * R_map_world_.transpose();
    C_map[s].translation() = R_map_world_ * C_world_by_seq[s].translation();
  }

  const int n = p.tile_cells;
  const double cell = p.cell_m;
  // Output tiles in (tj, ti) order: the output does not depend on hashing.
  std::map<std::pair<int, int>, std::vector<Acc>> acc;
  double sum_shift2 = 0.0, sum_dz2 = 0.0;
  for (const DemTile& t : in.tiles()) {
    for (int r = 0; r < n; ++r) {
      for (int c = 0; c < n; ++c) {
        const std::size_t k = static_cast<std::size_t>(r * n + c);
        const DemCell& cl = t.cells[k];
        if (cl.count == 0) continue;
        ++stats.cells_in;
        const int i = t.ti * n + c, j = t.tj * n + r;
        const Eigen::Vector3d p_map((i + 0.5) * cell, (j + 0.5) * cell, cl.height_m);
        const std::int32_t s = t.sources.empty() ? -1 : t.sources[k];
        Eigen::Vector3d q = p_map;
        if (s >= 0 && static_cast<std::size_t>(s) < C_map.size())
          q = C_map[static_cast<std::size_t>(s)] * p_map;
        else
          ++stats.cells_no_source;
        const double shift = std::hypot(q.x() - p_map.x(), q.y() - p_map.y());
        stats.max_shift_m = std::max(stats.max_shift_m, shift);
        sum_shift2 += shift * shift;
        sum_dz2 += (q.z() - p_map.z()) * (q.z() - p_map.z());

        const double var_indep = decodeVariance(cl.sigma_indep);
        const double w = var_indep > 0.0 ? 1.0 / var_indep : 1e12;
        const double var_pose = decodeVariance(cl.sigma_pose);
        const double lum = cl.luminance_8_8 / 256.0;
        const double u = q.x() / cell - 0.5, v = q.y() / cell - 0.5;
        const double fu = std::floor(u), fv = std::floor(v);
        const int i0 = static_cast<int>(fu), j0 = static_cast<int>(fv);
        const double au = u - fu, av = v - fv;
        for (int dj = 0; dj < 2; ++dj) {
          for (int di = 0; di < 2; ++di) {
            const double b = (di ? au : 1.0 - au) * (dj ? av : 1.0 - av);
            if (b <= 0.0) continue;
            const int oi = i0 + di, oj = j0 + dj;
            const int oti = out.tileOf(oi), otj = out.tileOf(oj);
            std::vector<Acc>& tile = acc[{otj, oti}];
            if (tile.empty()) tile.resize(static_cast<std::size_t>(n) * n);
            Acc& a = tile[static_cast<std::size_t>((oj - otj * n) * n + (oi - oti * n))];
            a.sum_bw += b * w;
            a.sum_bwh += b * w * q.z();
            a.sum_b += static_cast<float>(b);
            a.sum_bvp += static_cast<float>(b * var_pose);
            a.sum_bn += static_cast<float>(b * cl.count);
            a.sum_bnl += static_cast<float>(b * cl.count * lum);
          }
        }
      }
    }
  }
  if (stats.cells_in > 0) {
    stats.rms_shift_m = std::sqrt(sum_shift2 / static_cast<double>(stats.cells_in));
    stats.rms_dz_m = std::sqrt(sum_dz2 / static_cast<double>(stats.cells_in));
  }

  out.clear();
  for (auto& [key, tile_acc] : acc) {
    const int otj = key.first, oti = key.second;
    DemTile* t = nullptr;
    bool refused = false;
    for (int r = 0; r < n; ++r) {
      for (int c = 0; c < n; ++c) {
        const Acc& a = tile_acc[static_cast<std::size_t>(r * n + c)];
        if (!(a.sum_b >= params_.min_coverage) || !(a.sum_bw > 0.0)) continue;
        if (t == nullptr && !refused) {
          t = out.tileForWrite(oti, otj);
          refused = t == nullptr;
        }
        if (refused) {
          ++stats.cells_no_tile;
          continue;
        }
        DemCell& o = t->cells[static_cast<std::size_t>(r * n + c)];
        o.height_m = static_cast<float>(a.sum_bwh / a.sum_bw);
        o.sigma_indep = encodeVariance(a.sum_b / a.sum_bw);
        o.sigma_pose = encodeVariance(a.sum_bvp / a.sum_b);
        const double count = std::clamp(std::round(double{a.sum_bn} / a.sum_b), 1.0, 65535.0);
        o.count = static_cast<std::uint16_t>(count);
        const double lum = a.sum_bn > 0.0f ? a.sum_bnl / a.sum_bn : 0.0;
        o.luminance_8_8 = static_cast<std::uint16_t>(std::clamp(256.0 * lum + 0.5, 0.0, 65535.0));
        ++stats.cells_out;
      }
    }
    std::vector<Acc>().swap(tile_acc);  // free as we go
  }
  return Status::ok();
}

}  // namespace svslam::map
