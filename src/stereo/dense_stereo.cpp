#include "stereo/dense_stereo.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <string>

#include "stereo/prefilter.hpp"
#include "stereo/texture_filter.hpp"

namespace svslam {
namespace {

constexpr std::ptrdiff_t kXo = 32;  // column of x = 0 inside a cost plane (room for box padding)
constexpr std::uint16_t kImpossible = 0xFFFF;
constexpr int kPlaneBlock = 16;  // disparity planes per WTA pass (their agg rows stay in L1/L2)

std::ptrdiff_t roundUp(std::ptrdiff_t v, std::ptrdiff_t m) { return (v + m - 1) / m * m; }
int clampRow(int r, int h) { return std::clamp(r, 0, h - 1); }

}  // namespace

struct DenseStereo::Stripe {
  int y0 = 0;
  int y1 = 0;
  int ring_size = 0;
  AlignedBuffer<std::uint8_t> ring;  // ring_size cost rows of numDisp planes of ring_stride bytes
  std::vector<int> ring_row;         // image row held by each ring slot, -1 if none
  AlignedBuffer<std::uint16_t> colsum;  // numDisp planes of cost_stride_, x = 0 at kXo
  AlignedBuffer<std::uint16_t> agg;     // numDisp + 1 rows of agg_stride_: plane -1, planes
  AlignedBuffer<std::uint16_t> best, second, cm, cp, pm1, pm2, best_r;
  AlignedBuffer<std::int16_t> bidx, idx_r;
  std::vector<std::uint32_t> tex_col;
  std::vector<std::uint8_t> low_texture;         // 1 where the window's mean gradient is too low
  std::vector<std::uint32_t> prefilter_scratch;  // column sums of the mean-removal prefilter
  AlignedBuffer<std::uint8_t> census_planes;     // one row of byte-plane census, left then right
  int census_row = -1;                           // image row held in census_planes, -1 if none
  DenseStereoStats stats;

  simd::WtaRowState state() {
    return {best.data(), bidx.data(), second.data(), cm.data(),   cp.data(),
            pm1.data(),  pm2.data(),  best_r.data(), idx_r.data()};
  }
};

DenseStereo::~DenseStereo() = default;

DenseStereo::DenseStereo(const DenseStereoParams& params, int width, int height)
    : params_(params), width_(width), height_(height) {
  init_status_ = params_.validate();
  if (!init_status_) return;
  if (width <= 0 || height <= 0) {
    init_status_ = Status::invalidArgument("image size must be > 0");
    return;
  }
  if (params_.max_disp >= width) {
    init_status_ =
        Status::invalidArgument("max_disp (" + std::to_string(params_.max_disp) +
                                ") must be < image width (" + std::to_string(width) + ")");
    return;
  }
  k_ = &simd::kernels(params_.backend);
  census_planes_ = params_.census_byte_planes && k_->censusPlanesRow != nullptr &&
                   k_->censusPlanesCostRows != nullptr;
  census_nplanes_ = (params_.census_w * params_.census_h - 1 + 7) / 8;
  {
    // sigma_d for every possible parabola curvature numerator v = c- + c+ - 2 c0 (an integer up
    // to twice the largest aggregated cost): one table look-up per pixel instead of a search.
    const int max_denom = 2 * params_.maxPixelCost() * params_.window_w * params_.window_h;
    const float inv_area =
        static_cast<float>(1.0 / (static_cast<double>(params_.window_w) * params_.window_h));
    sigma_by_denom_.resize(static_cast<std::size_t>(max_denom) + 1);
    for (int v = 0; v <= max_denom; ++v) {
      sigma_by_denom_[static_cast<std::size_t>(v)] =
          params_.sigma_model.sigmaFor(static_cast<float>(v) * inv_area);
    }
  }
  const int D = params_.numDisp();
  const bool census = params_.cost == MatchingCost::kCensus;
  int need = 1;  // the texture gradient reads x +- 1
  if (census) need = std::max({need, params_.census_w / 2, params_.census_h / 2});
  if (!census && params_.prefilter == SadPrefilter::kMeanRemoval)
    need = std::max(need, params_.prefilter_size / 2);
  pad_x_ = need;
  pad_y_ = need;
  padded_left_.resize(width + 2 * pad_x_, height + 2 * pad_y_);
  padded_right_.resize(width + 2 * pad_x_, height + 2 * pad_y_);
  right_pad_ = static_cast<int>(roundUp(params_.max_disp, 8));
  row_stride_ = roundUp(right_pad_ + width + 8, 64);
  const std::size_t rows_n =
      static_cast<std::size_t>(row_stride_) * static_cast<std::size_t>(height);
  if (census && !census_planes_) {
    census_left_.resize(rows_n);
    census_right_.resize(rows_n);
  } else if (!census) {
    filt_left_.resize(rows_n);
    filt_right_.resize(rows_n);
  }
  cost_stride_ = roundUp(kXo + width + 32, 32);
  ring_stride_ = roundUp(width, 64);
  agg_stride_ = roundUp(width, 32);
  const int stripes = std::min(params_.num_stripes, height);
  for (int s = 0; s < stripes; ++s) {
    auto st = std::make_unique<Stripe>();
    st->y0 = static_cast<int>(static_cast<long>(height) * s / stripes);
    st->y1 = static_cast<int>(static_cast<long>(height) * (s + 1) / stripes);
    st->ring_size = params_.window_h + 1;
    st->ring.resize(static_cast<std::size_t>(D) * static_cast<std::size_t>(ring_stride_) *
                    static_cast<std::size_t>(st->ring_size));
    st->ring_row.assign(static_cast<std::size_t>(st->ring_size), -1);
    st->colsum.resize(static_cast<std::size_t>(D) * static_cast<std::size_t>(cost_stride_));
    const std::size_t wn = static_cast<std::size_t>(roundUp(width, 64));
    // Row 0: plane -1 (all 0xFFFF), row i + 1: plane i; slack for wtaNeighbours' 32-bit reads.
    st->agg.resize(static_cast<std::size_t>(D + 1) * static_cast<std::size_t>(agg_stride_) + 16);
    for (auto* b : {&st->best, &st->second, &st->cm, &st->cp, &st->pm1, &st->pm2, &st->best_r})
      b->resize(wn);
    st->bidx.resize(wn);
    st->idx_r.resize(wn + 16);  // finalizeRow reads idx_r at [0, width + 1)
    st->tex_col.assign(static_cast<std::size_t>(width), 0);
    st->low_texture.assign(static_cast<std::size_t>(width), 0);
    if (census && census_planes_)
      st->census_planes.resize(static_cast<std::size_t>(16 * row_stride_));
    st->prefilter_scratch.assign(static_cast<std::size_t>(width + params_.prefilter_size), 0);
    stripes_.push_back(std::move(st));
  }
}

void DenseStereo::padImage(ImageView<const std::uint8_t> src, ImageU8& dst, int y0, int y1) const {
  // Padded rows [y0, y1) of dst (which has pad_y_ extra rows on top and bottom).
  for (int py = y0; py < y1; ++py) {
    const std::uint8_t* s = src.row(clampRow(py - pad_y_, height_));
    std::uint8_t* d = dst.row(py);
    std::memset(d, s[0], static_cast<std::size_t>(pad_x_));
    std::memcpy(d + pad_x_, s, static_cast<std::size_t>(width_));
    std::memset(d + pad_x_ + width_, s[width_ - 1], static_cast<std::size_t>(pad_x_));
  }
}

void DenseStereo::prepareRows(Stripe& s) {
  const int y0 = s.y0;
  const int y1 = s.y1;
  const bool census = params_.cost == MatchingCost::kCensus;
  std::vector<std::uint32_t>& scratch = s.prefilter_scratch;  // sized in the constructor
  for (int y = y0; y < y1; ++y) {
    for (int side = 0; side < 2; ++side) {
      const ImageU8& padded = side == 0 ? padded_left_ : padded_right_;
      const std::uint8_t* center = padded.row(y + pad_y_) + pad_x_;
      const std::size_t off = static_cast<std::size_t>(y) * static_cast<std::size_t>(row_stride_) +
                              static_cast<std::size_t>(right_pad_);
      const std::uint8_t* win =
          center - (params_.census_h / 2) * padded.stride() - params_.census_w / 2;
      if (census && census_planes_) {
        break;  // byte-plane census rows are made in matchRows, where the costs need them
      } else if (census) {
        std::uint64_t* out = (side == 0 ? census_left_ : census_right_).data() + off;
        k_->censusRow(win, padded.stride(), width_, params_.census_w, params_.census_h, out);
        if (side == 1) std::fill(out - right_pad_, out, out[0]);
      } else {
        std::uint8_t* out = (side == 0 ? filt_left_ : filt_right_).data() + off;
        switch (params_.prefilter) {
          case SadPrefilter::kNone:
            copyRow(center, width_, out);
            break;
          case SadPrefilter::kXSobel:
            xSobelRow(center, padded.stride(), width_, params_.prefilter_cap, out);
            break;
          case SadPrefilter::kMeanRemoval:
            meanRemovalRow(center, padded.stride(), width_, params_.prefilter_size,
                           params_.prefilter_cap, scratch.data(), out);
            break;
        }
        if (side == 1) std::memset(out - right_pad_, out[0], static_cast<std::size_t>(right_pad_));
      }
    }
  }
}

void DenseStereo::censusPlanesRow(Stripe& s, int row, std::uint8_t* (&out)[2]) const {
  for (int side = 0; side < 2; ++side)
    out[side] = s.census_planes.data() + side * 8 * row_stride_ + right_pad_;
  if (s.census_row == row) return;
  for (int side = 0; side < 2; ++side) {
    const ImageU8& padded = side == 0 ? padded_left_ : padded_right_;
    const std::uint8_t* win =
        padded.row(row + pad_y_ - params_.census_h / 2) + pad_x_ - params_.census_w / 2;
    k_->censusPlanesRow(win, padded.stride(), width_, params_.census_w, params_.census_h, out[side],
                        row_stride_);
  }
  for (int j = 0; j < 8; ++j) {  // right planes: x < 0 replicates x = 0 (read at x - d)
    std::uint8_t* plane = out[1] + j * row_stride_;
    std::memset(plane - right_pad_, plane[0], static_cast<std::size_t>(right_pad_));
  }
  s.census_row = row;
}

std::uint8_t* DenseStereo::ringPlane(Stripe& s, int row, int i) const {
  const std::size_t slot = static_cast<std::size_t>(row % s.ring_size);
  return s.ring.data() +
         (slot * static_cast<std::size_t>(params_.numDisp()) + static_cast<std::size_t>(i)) *
             static_cast<std::size_t>(ring_stride_);
}

void DenseStereo::computeCostPlane(Stripe& s, int row, int i) const {
  const std::size_t off = static_cast<std::size_t>(row) * static_cast<std::size_t>(row_stride_) +
                          static_cast<std::size_t>(right_pad_);
  const int d = params_.min_disp + i;
  if (params_.cost == MatchingCost::kCensus)
    k_->censusCostRow(census_left_.data() + off, census_right_.data() + off, width_, d,
                      ringPlane(s, row, i));
  else
    k_->sadCostRow(filt_left_.data() + off, filt_right_.data() + off, width_, d,
                   ringPlane(s, row, i));
}

void DenseStereo::ensureCostRow(Stripe& s, int row) const {
  int& held = s.ring_row[static_cast<std::size_t>(row % s.ring_size)];
  if (held == row) return;
  if (params_.cost == MatchingCost::kCensus && census_planes_) {
    // All planes of the row at once (ring planes of a row are ring_stride_ apart).
    std::uint8_t* cen[2];
    censusPlanesRow(s, row, cen);
    k_->censusPlanesCostRows(cen[0], cen[1], row_stride_, census_nplanes_, width_, params_.min_disp,
                             params_.numDisp(), ringPlane(s, row, 0), ring_stride_);
  } else {
    for (int i = 0; i < params_.numDisp(); ++i) computeCostPlane(s, row, i);
  }
  held = row;
}

void DenseStereo::matchRows(Stripe& s, DisparityResult& out) {
  const int W = width_;
  const int D = params_.numDisp();
  const int d0 = params_.min_disp;
  const int rh = params_.window_h / 2;
  const int rw = params_.window_w / 2;
  const double area = static_cast<double>(params_.window_w) * params_.window_h;
  const bool use_texture = params_.texture_threshold > 0.0f;
  const double texture_limit = static_cast<double>(params_.texture_threshold) * 2.0 * area;
  std::fill(s.ring_row.begin(), s.ring_row.end(), -1);
  s.census_row = -1;  // a new frame: no census row is current
  simd::FinalizeCounts counts;
  simd::FinalizeParams fin{};
  fin.num_disp = D;
  fin.d0 = d0;
  fin.uniqueness_pct = params_.uniqueness_pct;
  fin.lr_check = params_.lr_check;
  fin.lr_max_diff = params_.lr_max_diff;
  fin.subpixel = params_.subpixel;
  fin.inv_area = static_cast<float>(1.0 / area);
  fin.sigma_by_denom = sigma_by_denom_.data();
  fin.max_denom = static_cast<int>(sigma_by_denom_.size()) - 1;

  const auto colsumPlane = [&](int i) {
    return s.colsum.data() + static_cast<std::size_t>(i) * static_cast<std::size_t>(cost_stride_);
  };
  // Texture column sums of left row r (gradients of the padded row: x +- 1 readable).
  auto texAdd = [&](int r, int sign) {
    addRowGradients(padded_left_.row(r + pad_y_) + pad_x_, W, sign, s.tex_col.data());
  };

  for (int y = s.y0; y < s.y1; ++y) {
    // 1-2. Vertical running sum of the cost planes over rows [y - rh, y + rh] (clamped),
    // then per plane the horizontal box and the streaming winner-take-all (3).
    const int new_row = clampRow(y + rh, height_);
    const int old_row = clampRow(y - rh - 1, height_);
    bool fresh_new = false;
    if (y == s.y0) {
      std::memset(s.colsum.data(), 0, s.colsum.size() * sizeof(std::uint16_t));
      if (use_texture) std::fill(s.tex_col.begin(), s.tex_col.end(), 0u);
      for (int r = y - rh; r <= y + rh; ++r) {
        const int rr = clampRow(r, height_);
        ensureCostRow(s, rr);
        for (int i = 0; i < D; ++i)
          k_->addSubRow(colsumPlane(i) + kXo, ringPlane(s, rr, i), nullptr,
                        static_cast<std::size_t>(W));
        if (use_texture) texAdd(rr, 1);
      }
    } else {
      fresh_new = s.ring_row[static_cast<std::size_t>(new_row % s.ring_size)] != new_row;
      if (use_texture) {
        texAdd(new_row, 1);
        texAdd(old_row, -1);
      }
    }
    // Planes of a ring row are ring_stride_ apart (one slot look-up per row, not per plane).
    std::uint8_t* const new_ring = ringPlane(s, new_row, 0);
    std::uint8_t* const old_ring = ringPlane(s, old_row, 0);
    const auto ringOffset = [&](int i) { return static_cast<std::ptrdiff_t>(i) * ring_stride_; };
    simd::wtaInitRow(s.state(), W);
    // Planes go through the WTA in blocks of kPlaneBlock (rows of s.agg, row 0 = plane -1).
    std::fill(s.agg.data(), s.agg.data() + agg_stride_, kImpossible);
    const simd::WtaRowState st = s.state();
    const bool planes_block = fresh_new && census_planes_ && params_.cost == MatchingCost::kCensus;
    for (int i0 = 0; i0 < D; i0 += kPlaneBlock) {
      const int n = std::min(kPlaneBlock, D - i0);
      if (planes_block) {
        // The block's cost planes of the entering row in one pass (left census in registers);
        // they are consumed right below while still in L1.
        std::uint8_t* cen[2];
        censusPlanesRow(s, new_row, cen);
        k_->censusPlanesCostRows(cen[0], cen[1], row_stride_, census_nplanes_, W, d0 + i0, n,
                                 new_ring + ringOffset(i0), ring_stride_);
      }
      // The block's running sums, then its border fills, then its boxes: a fill reads back the
      // end of a row addSubRow has just stored in vectors, and the box reads the fill's small
      // stores in vectors; either stalls (no store forwarding) unless other work comes between.
      for (int i = i0; y != s.y0 && i < i0 + n; ++i) {
        if (fresh_new && !planes_block) computeCostPlane(s, new_row, i);
        k_->addSubRow(colsumPlane(i) + kXo, new_ring + ringOffset(i), old_ring + ringOffset(i),
                      static_cast<std::size_t>(W));
      }
      for (int i = i0; i < i0 + n; ++i) {
        std::uint16_t* col = colsumPlane(i);
        std::fill(col + kXo - rw, col + kXo, col[kXo]);
        std::fill(col + kXo + W, col + kXo + W + rw, col[kXo + W - 1]);
      }
      for (int i = i0; i < i0 + n; ++i) {
        std::uint16_t* agg =
            s.agg.data() + static_cast<std::size_t>(i + 1) * static_cast<std::size_t>(agg_stride_);
        k_->boxRow(colsumPlane(i) + kXo - rw, W, params_.window_w, agg);
        std::fill(agg, agg + std::min(W, d0 + i), kImpossible);  // x - d < 0: no match possible
      }
      k_->wtaUpdateRows(
          s.agg.data() + static_cast<std::size_t>(i0 + 1) * static_cast<std::size_t>(agg_stride_),
          agg_stride_, n, i0, W, d0, st);
    }
    // Costs at d_best -+ 1 for the parabola, from the stored planes.
    k_->wtaNeighbours(s.agg.data() + agg_stride_, agg_stride_, D, W, st);
    if (fresh_new) s.ring_row[static_cast<std::size_t>(new_row % s.ring_size)] = new_row;
    if (use_texture) markLowTexture(s.tex_col.data(), W, rw, texture_limit, s.low_texture.data());
    // 4-5. Filters and sub-pixel refinement.
    k_->finalizeRow(s.state(), use_texture ? s.low_texture.data() : nullptr, W, fin,
                    out.disparity_px.row(y), out.sigma_d_px.row(y), out.curvature.row(y), counts);
  }
  s.stats.no_candidate = counts.no_candidate;
  s.stats.low_texture = counts.low_texture;
  s.stats.not_unique = counts.not_unique;
  s.stats.lr_inconsistent = counts.lr_inconsistent;
  s.stats.valid = counts.valid;
}

void DenseStereo::prepareOutput(DisparityResult& out) const {
  out.disparity_px.resize(width_, height_);
  out.sigma_d_px.resize(width_, height_);
  out.curvature.resize(width_, height_);
}

Status DenseStereo::process(ImageView<const std::uint8_t> left, ImageView<const std::uint8_t> right,
                            DisparityResult& out) {
  SerialExecutor serial;
  return process(left, right, out, serial);
}

Status DenseStereo::process(ImageView<const std::uint8_t> left, ImageView<const std::uint8_t> right,
                            DisparityResult& out, Executor& executor) {
  if (!init_status_) return init_status_;
  if (left.empty() || right.empty()) return Status::invalidArgument("empty input image");
  if (left.width != width_ || left.height != height_ || right.width != width_ ||
      right.height != height_)
    return Status::invalidArgument(
        "image size mismatch: stage built for " + std::to_string(width_) + "x" +
        std::to_string(height_) + ", got left " + std::to_string(left.width) + "x" +
        std::to_string(left.height) + " and right " + std::to_string(right.width) + "x" +
        std::to_string(right.height));
  prepareOutput(out);

  // The task lambdas capture two pointers only (the executor takes them by reference anyway).
  struct Frame {
    ImageView<const std::uint8_t> left, right;
    DisparityResult* out;
  } frame{left, right, &out};
  const int n = static_cast<int>(stripes_.size());
  executor.parallelFor(n, [this, &frame](int t) {
    const int padded_h = height_ + 2 * pad_y_;
    const int n_tasks = static_cast<int>(stripes_.size());
    const int y0 = static_cast<int>(static_cast<long>(padded_h) * t / n_tasks);
    const int y1 = static_cast<int>(static_cast<long>(padded_h) * (t + 1) / n_tasks);
    padImage(frame.left, padded_left_, y0, y1);
    padImage(frame.right, padded_right_, y0, y1);
  });
  executor.parallelFor(n, [this](int t) { prepareRows(*stripes_[static_cast<std::size_t>(t)]); });
  executor.parallelFor(
      n, [this, &frame](int t) { matchRows(*stripes_[static_cast<std::size_t>(t)], *frame.out); });

  DenseStereoStats total;
  for (const auto& s : stripes_) {
    total.valid += s->stats.valid;
    total.no_candidate += s->stats.no_candidate;
    total.low_texture += s->stats.low_texture;
    total.not_unique += s->stats.not_unique;
    total.lr_inconsistent += s->stats.lr_inconsistent;
  }
  total.backend = k_->name;
  out.stats = total;
  return Status::ok();
}

}  // namespace svslam
