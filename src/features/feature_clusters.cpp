#include "features/feature_clusters.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace svslam {
namespace {

// Pixels [floor(u - r), floor(u + r)] x [floor(v - r), floor(v + r)], clipped to w x h (clamped
// in double first so far-away projections cannot overflow int).
RoiRect squareAround(double u, double v, double r, int w, int h) {
  auto lo = [](double a, int size) {
    return static_cast<int>(std::clamp(std::floor(a), 0.0, static_cast<double>(size)));
  };
  auto hi = [](double a, int size) {
    return static_cast<int>(std::clamp(std::floor(a) + 1.0, 0.0, static_cast<double>(size)));
  };
  return {lo(u - r, w), lo(v - r, h), hi(u + r, w), hi(v + r, h)};
}

}  // namespace

Status FeatureClusterParams::validate() const {
  if (!(stop_distance_m > 0) || !std::isfinite(stop_distance_m))
    return Status::invalidArgument("stop_distance_m must be finite and > 0");
  if (min_cluster_size < 1) return Status::invalidArgument("min_cluster_size must be >= 1");
  if (max_points < 1 || max_points > 4096)
    return Status::invalidArgument("max_points must be in 1..4096");
  if (!(roi_margin_px >= 0 && roi_margin_px <= 1000))
    return Status::invalidArgument("roi_margin_px must be in 0..1000");
  if (roi_radius != RoiRadius::kSphereBound && roi_radius != RoiRadius::kFarthestPoint)
    return Status::invalidArgument("roi_radius is not a RoiRadius value");
  if (!(min_depth_m > 0) || !std::isfinite(min_depth_m))
    return Status::invalidArgument("min_depth_m must be finite and > 0");
  if (unknown_cell_px < 4 || unknown_cell_px > 1024)
    return Status::invalidArgument("unknown_cell_px must be in 4..1024");
  return Status::ok();
}

bool RoiSet::insideAnyRoi(double u, double v) const {
  return std::any_of(rois.begin(), rois.end(),
                     [&](const ClusterRoi& r) { return r.left.contains(u, v); });
}

bool RoiSet::insideAnyRightRoi(double u, double v) const {
  return std::any_of(rois.begin(), rois.end(),
                     [&](const ClusterRoi& r) { return r.right.contains(u, v); });
}

bool RoiSet::isUnknown(double u, double v) const {
  if (!(u >= 0 && u < width && v >= 0 && v < height)) return false;
  return unknownCell(static_cast<int>(u) / cell_px, static_cast<int>(v) / cell_px);
}

FeatureClusters::FeatureClusters(const FeatureClusterParams& params) : params_(params) {
  init_status_ = params_.validate();
  if (!init_status_) return;
  const auto m = static_cast<std::size_t>(params_.max_points);
  dist_.resize(m * m);
  for (auto* v : {&index_, &open_, &open_pos_, &chain_, &next_, &tail_, &label_}) v->reserve(m);
  alive_.reserve(m);
  height_.reserve(m);
  qsum_.reserve(m);
  xyz_.reserve(3 * m);
  sq_.reserve(m);
}

void FeatureClusters::closeCluster(int a) {
  const int pos = open_pos_[static_cast<std::size_t>(a)];
  const int last = open_.back();
  open_[static_cast<std::size_t>(pos)] = last;
  open_pos_[static_cast<std::size_t>(last)] = pos;
  open_.pop_back();
  open_pos_[static_cast<std::size_t>(a)] = -1;
}

// Merges clusters a and b into the one of smaller index; Lance-Williams update of its row and
// column over the open clusters: D(k, a u b) = max(D(k, a), D(k, b)).
void FeatureClusters::merge(int a, int b) {
  const int keep = std::min(a, b), gone = std::max(a, b);
  const float h = dist(a, b);
  for (const int k : open_) {
    if (k == a || k == b) continue;
    const float v = std::max(dist(a, k), dist(b, k));
    dist(keep, k) = v;
    dist(k, keep) = v;
  }
  closeCluster(gone);
  const auto ik = static_cast<std::size_t>(keep), ig = static_cast<std::size_t>(gone);
  alive_[ig] = 0;
  height_[ik] = h;
  next_[static_cast<std::size_t>(tail_[ik])] = gone;
  tail_[ik] = tail_[ig];
}

Status FeatureClusters::process(const std::vector<Eigen::Vector3d>& points,
                                const std::vector<float>& quality, std::vector<Cluster>& out) {
  if (!init_status_) {
    out.clear();
    return init_status_;
  }
  if (!quality.empty() && quality.size() != points.size()) {
    out.clear();
    return Status::invalidArgument("quality must be empty or hold one value per point");
  }
  for (const auto& p : points)
    if (!p.allFinite()) {
      out.clear();
      return Status::invalidArgument("points contain NaN or infinity");
    }
  const auto n_in = static_cast<std::int64_t>(points.size());
  n_ = static_cast<int>(std::min<std::int64_t>(n_in, params_.max_points));
  const auto n = static_cast<std::size_t>(n_);
  index_.resize(n);
  for (std::size_t k = 0; k < n; ++k)
    index_[k] = static_cast<int>(static_cast<std::int64_t>(k) * n_in / n_);

  // Pairwise distances d(i, j) = sqrt(dx^2 + dy^2 + dz^2) in double, rounded to float; one
  // whole row at a time (symmetric by construction: only the signs of dx, dy, dz change).
  xyz_.resize(3 * n);
  sq_.resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    const Eigen::Vector3d& p = points[static_cast<std::size_t>(index_[k])];
    xyz_[k] = p.x();
    xyz_[n + k] = p.y();
    xyz_[2 * n + k] = p.z();
  }
  using ArrayMap = Eigen::Map<const Eigen::ArrayXd>;
  const ArrayMap xs(xyz_.data(), n_), ys(xyz_.data() + n, n_), zs(xyz_.data() + 2 * n, n_);
  Eigen::Map<Eigen::ArrayXd> sq(sq_.data(), n_);
  for (int i = 0; i < n_; ++i) {  // Eigen's packet sqrt is the correctly rounded one
    sq = (xs - xs(i)).square() + (ys - ys(i)).square() + (zs - zs(i)).square();
    sq = sq.sqrt();
    Eigen::Map<Eigen::ArrayXf>(&dist(i, 0), n_) = sq.cast<float>();
  }
  open_.resize(n);
  open_pos_.resize(n);
  alive_.assign(n, 1);
  height_.assign(n, 0.0f);
  next_.assign(n, -1);
  tail_.resize(n);
  for (int i = 0; i < n_; ++i) {
    const auto s = static_cast<std::size_t>(i);
    open_[s] = i;
    open_pos_[s] = i;
    tail_[s] = i;
  }
  chain_.clear();

  // Nearest-neighbour chain: grow the chain by nearest neighbours until the top two are mutual
  // nearest neighbours, then merge them. When the top's nearest neighbour is beyond the stop
  // distance, so is every chain element's (chain distances never increase and later merges only
  // raise distances), and the whole chain is closed.
  const double stop = params_.stop_distance_m;
  while (!open_.empty()) {
    if (chain_.empty()) chain_.push_back(open_.front());
    const int a = chain_.back();
    const int prev = chain_.size() >= 2 ? chain_[chain_.size() - 2] : -1;
    const float* row = &dist(a, 0);
    int best = -1;
    float best_d = std::numeric_limits<float>::infinity();
    for (const int k : open_) {
      if (k == a) continue;
      const float dk = row[k];
      if (dk < best_d || (dk == best_d && k < best)) {
        best = k;
        best_d = dk;
      }
    }
    if (prev >= 0 && row[prev] <= best_d) best = prev;  // ties go to the chain: no cycles
    if (best < 0 || static_cast<double>(best_d) > stop) {
      for (const int c : chain_) closeCluster(c);
      chain_.clear();
    } else if (best == prev) {
      chain_.resize(chain_.size() - 2);
      merge(a, prev);
    } else {
      chain_.push_back(best);
    }
  }

  // Label the kept clusters in order of their smallest member (the representative), then fill
  // them in one ascending pass so the member lists come out sorted.
  label_.assign(n, -1);
  int count = 0;
  for (int i = 0; i < n_; ++i) {
    if (!alive_[static_cast<std::size_t>(i)]) continue;
    int size = 0;
    for (int j = i; j >= 0; j = next_[static_cast<std::size_t>(j)]) ++size;
    if (size < params_.min_cluster_size) continue;
    for (int j = i; j >= 0; j = next_[static_cast<std::size_t>(j)])
      label_[static_cast<std::size_t>(j)] = count;
    ++count;
  }
  out.resize(static_cast<std::size_t>(count));
  qsum_.assign(static_cast<std::size_t>(count), 0.0);
  for (auto& c : out) {
    c.members.clear();
    c.centre_m.setZero();
  }
  for (int i = 0; i < n_; ++i) {
    const int l = label_[static_cast<std::size_t>(i)];
    if (l < 0) continue;
    Cluster& c = out[static_cast<std::size_t>(l)];
    const int idx = index_[static_cast<std::size_t>(i)];
    if (c.members.empty()) c.diameter_m = height_[static_cast<std::size_t>(i)];
    c.members.push_back(idx);
    c.centre_m += points[static_cast<std::size_t>(idx)];
    if (!quality.empty())
      qsum_[static_cast<std::size_t>(l)] += quality[static_cast<std::size_t>(idx)];
  }
  for (std::size_t l = 0; l < out.size(); ++l) {
    Cluster& c = out[l];
    const double m = static_cast<double>(c.members.size());
    c.centre_m /= m;
    c.mean_quality = static_cast<float>(qsum_[l] / m);
    double best = -1;
    for (const int idx : c.members) {
      const double d2 = (points[static_cast<std::size_t>(idx)] - c.centre_m).squaredNorm();
      if (d2 > best) {
        best = d2;
        c.farthest_m = points[static_cast<std::size_t>(idx)];
      }
    }
    c.radius_m = std::sqrt(best);
  }
  return Status::ok();
}

Status FeatureClusters::project(const std::vector<Cluster>& clusters,
                                const Eigen::Isometry3d& T_cur_prev, const StereoCalibration& calib,
                                RoiSet& out) const {
  out.rois.clear();
  if (!init_status_) return init_status_;
  if (Status s = calib.validate(); !s) return s;
  if (!T_cur_prev.matrix().allFinite())
    return Status::invalidArgument("T_cur_prev contains NaN or infinity");
  for (const auto& c : clusters)
    if (!c.centre_m.allFinite() || !c.farthest_m.allFinite() || !(c.radius_m >= 0) ||
        !std::isfinite(c.radius_m))
      return Status::invalidArgument("cluster geometry contains NaN, infinity or radius < 0");
  const int w = calib.width, h = calib.height, cell = params_.unknown_cell_px;
  out.width = w;
  out.height = h;
  out.cell_px = cell;
  out.cols = (w + cell - 1) / cell;
  out.rows = (h + cell - 1) / cell;
  out.unknown.assign(static_cast<std::size_t>(out.cols) * static_cast<std::size_t>(out.rows), 1);

  const double f = calib.f_px, b = calib.baseline_m, zmin = params_.min_depth_m;
  for (std::size_t i = 0; i < clusters.size(); ++i) {
    const Cluster& cl = clusters[i];
    const Eigen::Vector3d c = T_cur_prev * cl.centre_m;  // current left camera frame, metres
    if (!(c.z() >= zmin)) continue;                      // behind (or too near) the camera
    ClusterRoi roi;
    roi.cluster = static_cast<int>(i);
    roi.centre_px = {f * c.x() / c.z() + calib.cx_px, f * c.y() / c.z() + calib.cy_px};
    roi.disparity_px = f * b / c.z();
    double radius = -1;  // < 0: no bound
    if (params_.roi_radius == RoiRadius::kSphereBound) {
      const double r = cl.radius_m, z = c.z();
      if (z - r >= zmin) {
        const double reach = std::max(c.norm(), (c - Eigen::Vector3d(b, 0, 0)).norm());
        radius = f * r * reach / (z * (z - r));
      }
    } else {
      const Eigen::Vector3d fp = T_cur_prev * cl.farthest_m;
      if (fp.z() >= zmin) {
        const Eigen::Vector2d pf(f * fp.x() / fp.z() + calib.cx_px,
                                 f * fp.y() / fp.z() + calib.cy_px);
        radius = (pf - roi.centre_px).norm();
      }
    }
    if (radius >= 0) {
      roi.radius_px = radius + params_.roi_margin_px;
      const double u = roi.centre_px.x(), v = roi.centre_px.y();
      roi.left = squareAround(u, v, roi.radius_px, w, h);
      if (roi.left.empty()) continue;  // outside the image
      roi.right = squareAround(u - roi.disparity_px, v, roi.radius_px, w, h);
    } else {
      roi.whole_image = true;
      roi.left = roi.right = RoiRect{0, 0, w, h};
    }
    for (int cy = roi.left.y0 / cell; cy <= (roi.left.y1 - 1) / cell; ++cy)
      for (int cx = roi.left.x0 / cell; cx <= (roi.left.x1 - 1) / cell; ++cx)
        out.unknown[static_cast<std::size_t>(cy * out.cols + cx)] = 0;
    out.rois.push_back(roi);
  }
  return Status::ok();
}

}  // namespace svslam
