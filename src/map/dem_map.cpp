#include "map/dem_map.hpp"

#include <algorithm>
#include <cstdio>
#include <cmath>
#include <limits>

namespace svslam::map {

namespace {
constexpr double kSigmaCodeScale = 1024.0;
constexpr double kSigmaCodeOffset = 20.0;
constexpr std::uint32_t kMaxCount = 65535;
}  // namespace

std::uint16_t encodeSigma(double sigma_m) {
  if (!(sigma_m > 0.0)) return 0;  // 0, negative, NaN
  const double c = std::round((std::log2(sigma_m) + kSigmaCodeOffset) * kSigmaCodeScale);
  return static_cast<std::uint16_t>(std::clamp(c, 1.0, 65535.0));
}

std::uint16_t encodeVariance(double var_m2) {
  if (!(var_m2 > 0.0)) return 0;
  // log2(sigma) = log2(var) / 2; float precision is far below the 0.07 % step.
  const float c = std::round(
      (0.5f * std::log2(static_cast<float>(var_m2)) + static_cast<float>(kSigmaCodeOffset)) *
      static_cast<float>(kSigmaCodeScale));
  return static_cast<std::uint16_t>(std::clamp(c, 1.0f, 65535.0f));
}

double decodeSigma(std::uint16_t code) {
  if (code == 0) return 0.0;
  return std::exp2(static_cast<double>(code) / kSigmaCodeScale - kSigmaCodeOffset);
}

float decodeVariance(std::uint16_t code) {
  static const std::vector<float> table = [] {
    std::vector<float> t(65536);
    for (std::size_t c = 0; c < t.size(); ++c) {
      const double s = decodeSigma(static_cast<std::uint16_t>(c));
      t[c] = static_cast<float>(s * s);
    }
    return t;
  }();
  return table[code];
}

DemMap::DemMap(const DemParams& params)
    : params_(params),
      init_status_(params.validate()),
      min_var_(static_cast<float>(params.min_sigma_m * params.min_sigma_m)) {
  if (init_status_.isOk()) {
    tiles_.reserve(static_cast<std::size_t>(params_.max_tiles));
    index_.reserve(static_cast<std::size_t>(params_.max_tiles));
  }
}

int DemMap::tileOf(int i) const {
  const int n = params_.tile_cells;
  return i >= 0 ? i / n : -((-i + n - 1) / n);
}

const DemTile* DemMap::tile(int ti, int tj) const {
  const std::uint64_t k = key(ti, tj);
  if (last_slot_ >= 0 && k == last_key_) return &tiles_[static_cast<std::size_t>(last_slot_)];
  const auto it = index_.find(k);
  if (it == index_.end()) return nullptr;
  last_key_ = k;
  last_slot_ = it->second;
  return &tiles_[static_cast<std::size_t>(it->second)];
}

DemTile* DemMap::tileForWrite(int ti, int tj) {
  if (const DemTile* t = tile(ti, tj)) return const_cast<DemTile*>(t);
  if (static_cast<int>(tiles_.size()) >= params_.max_tiles) return nullptr;
  DemTile t;
  t.ti = ti;
  t.tj = tj;
  const auto n = static_cast<std::size_t>(params_.tile_cells);
  t.cells.assign(n * n, DemCell{});
  if (params_.keep_cell_sources) t.sources.assign(n * n, -1);
  const int slot = static_cast<int>(tiles_.size());
  tiles_.push_back(std::move(t));
  index_.emplace(key(ti, tj), slot);
  last_key_ = key(ti, tj);
  last_slot_ = slot;
  return &tiles_.back();
}

const DemCell* DemMap::cell(int i, int j) const {
  const int ti = tileOf(i), tj = tileOf(j);
  const DemTile* t = tile(ti, tj);
  if (t == nullptr) return nullptr;
  const int n = params_.tile_cells;
  return &t->cells[static_cast<std::size_t>((j - tj * n) * n + (i - ti * n))];
}

bool DemMap::estimate(int i, int j, double& height_m, double& sigma_m) const {
  const DemCell* c = cell(i, j);
  if (c == nullptr || c->count == 0) return false;
  height_m = c->height_m;
  sigma_m = totalSigma(*c);
  return true;
}

double DemMap::totalSigma(const DemCell& c) const {
  const double si = decodeSigma(c.sigma_indep), sp = decodeSigma(c.sigma_pose);
  return std::sqrt(si * si + sp * sp + params_.min_sigma_m * params_.min_sigma_m);
}

bool DemMap::fuse(int i, int j, const CellMeasurement& m, std::int64_t seq, std::int64_t t_ns) {
  if (m.count == 0 || !(m.sum_w > 0.0)) return true;
  const int ti = tileOf(i), tj = tileOf(j);
  DemTile* t = tileForWrite(ti, tj);
  if (t == nullptr) return false;
  const int n = params_.tile_cells;
  const auto k = static_cast<std::size_t>((j - tj * n) * n + (i - ti * n));
  fuseCell(t->cells[k], m, params_.reject_variance_factor);
  recordSource(*t, k, seq);
  touch(*t, seq, t_ns);
  return true;
}

void DemMap::fuseCell(DemCell& c, const CellMeasurement& m, double reject_variance_factor) {
  if (m.count == 0 || !(m.sum_w > 0.0)) return;
  if (c.count == 0) {
    c.height_m = static_cast<float>(m.sum_wh / m.sum_w);
    c.sigma_indep = encodeVariance(1.0 / m.sum_w);
    c.sigma_pose = encodeVariance(m.sum_var_pose / m.count);
    c.count = static_cast<std::uint16_t>(std::min(m.count, kMaxCount));
    c.luminance_8_8 = static_cast<std::uint16_t>(
        std::min<std::uint32_t>((256u * m.sum_luminance + m.count / 2) / m.count, 65535u));
    return;
  }
  double vi = decodeVariance(c.sigma_indep);
  if (2 * m.gated > m.count) vi *= reject_variance_factor;  // most of the frame rejects the cell
  const double w_old = vi > 0.0 ? 1.0 / vi : 0.0;
  const double w = w_old + m.sum_w;
  c.height_m = static_cast<float>((w_old * c.height_m + m.sum_wh) / w);
  c.sigma_indep = encodeVariance(1.0 / w);
  // Means over the points: the old cell counts as min(count, 65535) points.
  const double n_old = c.count, n_new = n_old + m.count;
  c.sigma_pose = encodeVariance((n_old * decodeVariance(c.sigma_pose) + m.sum_var_pose) / n_new);
  const double lum = (n_old * c.luminance_8_8 + 256.0 * m.sum_luminance) / n_new;
  c.luminance_8_8 = static_cast<std::uint16_t>(std::min(lum + 0.5, 65535.0));
  c.count = static_cast<std::uint16_t>(std::min<double>(n_new, kMaxCount));
}

void DemMap::touch(DemTile& t, std::int64_t seq, std::int64_t t_ns) {
  if (t.first_seq < 0) t.first_seq = seq;
  t.last_seq = seq;
  t.last_t_ns = t_ns;
}

std::size_t DemMap::bytes() const {
  const auto n = static_cast<std::size_t>(params_.tile_cells);
  const std::size_t per_cell =
      sizeof(DemCell) + (params_.keep_cell_sources ? sizeof(std::int32_t) : 0);
  return tiles_.size() * n * n * per_cell;
}

void DemMap::fillRaster(const DemTile& t, DemRaster& out) const {
  const int n = params_.tile_cells;
  for (int r = 0; r < n; ++r) {
    for (int c = 0; c < n; ++c) {
      const DemCell& cell = t.cells[static_cast<std::size_t>(r * n + c)];
      if (cell.count == 0) continue;
      int col = 0, row = 0;
      if (!out.cellToPixel(t.ti * n + c, t.tj * n + r, col, row)) continue;
      const std::size_t k = out.index(col, row);
      out.height_m[k] = cell.height_m;
      out.sigma_m[k] = static_cast<float>(totalSigma(cell));
      out.count[k] = cell.count;
      out.luminance[k] =
          static_cast<std::uint8_t>(std::clamp((cell.luminance_8_8 + 128) / 256, 0, 255));
    }
  }
}

Status DemMap::toRaster(DemRaster& out) const {
  out.cell_m = params_.cell_m;
  out.i0 = out.j0 = 0;
  out.resize(0, 0);
  if (tiles_.empty()) return Status::ok();
  int ti0 = std::numeric_limits<int>::max(), tj0 = ti0;
  int ti1 = std::numeric_limits<int>::min(), tj1 = ti1;
  for (const DemTile& t : tiles_) {
    ti0 = std::min(ti0, t.ti);
    tj0 = std::min(tj0, t.tj);
    ti1 = std::max(ti1, t.ti);
    tj1 = std::max(tj1, t.tj);
  }
  const int n = params_.tile_cells;
  const double cols = (static_cast<double>(ti1) - ti0 + 1) * n;
  const double rows = (static_cast<double>(tj1) - tj0 + 1) * n;
  if (cols * rows > params_.max_raster_mcells * 1e6) {
    char msg[256];
    std::snprintf(msg, sizeof msg,
                  "elevation map spans %.0f x %.0f cells (%.0f x %.0f m), more than "
                  "map.max_raster_mcells = %d million: not written (diverged trajectory?)",
                  cols, rows, cols * params_.cell_m, rows * params_.cell_m,
                  params_.max_raster_mcells);
    return Status::failedPrecondition(msg);
  }
  out.i0 = ti0 * n;
  out.j0 = tj0 * n;
  out.resize(static_cast<int>(cols), static_cast<int>(rows));
  for (const DemTile& t : tiles_) fillRaster(t, out);
  return Status::ok();
}

void DemMap::emptyTileRaster(int ti, int tj, DemRaster& out) const {
  const int n = params_.tile_cells;
  out.cell_m = params_.cell_m;
  out.i0 = ti * n;
  out.j0 = tj * n;
  if (out.cols != n || out.rows != n) out.resize(n, n);
  std::fill(out.height_m.begin(), out.height_m.end(), NAN);
  std::fill(out.sigma_m.begin(), out.sigma_m.end(), NAN);
  std::fill(out.count.begin(), out.count.end(), 0.0f);
  std::fill(out.luminance.begin(), out.luminance.end(), std::uint8_t{0});
}

void DemMap::tileRaster(const DemTile& t, DemRaster& out) const {
  emptyTileRaster(t.ti, t.tj, out);
  fillRaster(t, out);
}

void DemMap::clear() {
  tiles_.clear();
  index_.clear();
  last_key_ = ~0ull;
  last_slot_ = -1;
}

}  // namespace svslam::map
