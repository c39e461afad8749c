#include "features/delaunay.hpp"

#include <algorithm>
#include <cmath>

namespace svslam {
namespace {

// Circumcircle of (a, b, c), computed in coordinates relative to a (keeps the squared terms
// small next to the far super-triangle); r2 = +inf for collinear points (always "contains").
void circumcircle(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c,
                  double& cx, double& cy, double& r2) {
  const Eigen::Vector2d B = b - a, C = c - a;
  const double d = 2.0 * (B.x() * C.y() - B.y() * C.x());
  if (std::abs(d) < 1e-12) {
    cx = cy = 0;
    r2 = HUGE_VAL;
    return;
  }
  const double b2 = B.squaredNorm(), c2 = C.squaredNorm();
  const double ux = (C.y() * b2 - B.y() * c2) / d;
  const double uy = (B.x() * c2 - C.x() * b2) / d;
  cx = a.x() + ux;
  cy = a.y() + uy;
  r2 = ux * ux + uy * uy;
}

}  // namespace

Status Delaunay::process(const std::vector<Eigen::Vector2d>& pts, std::vector<Triangle2>& out) {
  out.clear();
  const int n = static_cast<int>(pts.size());
  if (n < 3) return Status::ok();
  double minx = pts[0].x(), maxx = minx, miny = pts[0].y(), maxy = miny;
  for (const auto& q : pts) {
    if (!std::isfinite(q.x()) || !std::isfinite(q.y()))
      return Status::invalidArgument("delaunay: point is not finite");
    minx = std::min(minx, q.x());
    maxx = std::max(maxx, q.x());
    miny = std::min(miny, q.y());
    maxy = std::max(maxy, q.y());
  }
  const double span = std::max({maxx - minx, maxy - miny, 1.0});
  const double mx = 0.5 * (minx + maxx), my = 0.5 * (miny + maxy);
  p_.assign(pts.begin(), pts.end());
  // The super-triangle must be far enough that no circumcircle of three nearly collinear hull
  // points reaches its corners (else hull triangles are lost), yet near enough that the
  // circumcircle tests of co-circular input points keep their precision: 1e3 spans (tested on
  // random sets and on a grid).
  constexpr double kFar = 1e3;
  p_.emplace_back(mx - kFar * span, my - span);
  p_.emplace_back(mx + kFar * span, my - span);
  p_.emplace_back(mx, my + kFar * span);
  tris_.clear();
  auto add = [&](int a, int b, int c) {
    Work w{a, b, c, 0, 0, 0};
    circumcircle(p_[a], p_[b], p_[c], w.cx, w.cy, w.r2);
    tris_.push_back(w);
  };
  add(n, n + 1, n + 2);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector2d& q = p_[i];
    bool duplicate = false;
    edges_.clear();
    keep_.clear();
    for (const Work& t : tris_) {
      const double dx = q.x() - t.cx, dy = q.y() - t.cy;
      if (dx * dx + dy * dy <= t.r2) {
        if (q == p_[t.a] || q == p_[t.b] || q == p_[t.c]) duplicate = true;
        edges_.push_back({t.a, t.b});
        edges_.push_back({t.b, t.c});
        edges_.push_back({t.c, t.a});
      } else {
        keep_.push_back(t);
      }
    }
    if (duplicate || edges_.empty()) continue;
    // Boundary of the cavity: the edges that belong to one bad triangle only.
    tris_.swap(keep_);
    for (std::size_t e = 0; e < edges_.size(); ++e) {
      bool shared = false;
      for (std::size_t f = 0; f < edges_.size() && !shared; ++f)
        shared = f != e && edges_[f][0] == edges_[e][1] && edges_[f][1] == edges_[e][0];
      if (!shared) add(edges_[e][0], edges_[e][1], i);
    }
  }
  for (const Work& t : tris_)
    if (t.a < n && t.b < n && t.c < n) out.push_back({{t.a, t.b, t.c}});
  return Status::ok();
}

int Delaunay::locate(const std::vector<Eigen::Vector2d>& pts, const std::vector<Triangle2>& tris,
                     const Eigen::Vector2d& p, Eigen::Vector3d& bary) {
  // The triangle whose smallest barycentric coordinate is largest: exact containment gives
  // >= 0; a point on a shared edge may come out slightly negative in every triangle after
  // rounding (e.g. with fused multiply-add), hence the tolerance.
  constexpr double kEps = 1e-7;
  int best = -1;
  double best_min = -kEps;
  for (std::size_t k = 0; k < tris.size(); ++k) {
    const Eigen::Vector2d& a = pts[static_cast<std::size_t>(tris[k].v[0])];
    const Eigen::Vector2d& b = pts[static_cast<std::size_t>(tris[k].v[1])];
    const Eigen::Vector2d& c = pts[static_cast<std::size_t>(tris[k].v[2])];
    const double det = (b.x() - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (b.y() - a.y());
    if (std::abs(det) < 1e-12) continue;
    const double l1 = ((p.x() - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (p.y() - a.y())) / det;
    const double l2 = ((b.x() - a.x()) * (p.y() - a.y()) - (p.x() - a.x()) * (b.y() - a.y())) / det;
    const double l0 = 1.0 - l1 - l2;
    const double m = std::min({l0, l1, l2});
    if (m >= best_min) {
      best_min = m;
      best = static_cast<int>(k);
      bary = {l0, l1, l2};
      if (m >= 0.0) return best;  // strictly inside (or on the boundary): done
    }
  }
  return best;
}

}  // namespace svslam
