// Delaunay triangulation (Bowyer-Watson) checked against independent references: a
// monotone-chain convex hull, the Euler relation, and brute-force empty-circumcircle tests.
#include "features/delaunay.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <set>
#include <string>
#include <vector>

namespace svslam {
namespace {

// ------------------------------------------------------------------------------------------
// Delaunay
// ------------------------------------------------------------------------------------------

using Pts = std::vector<Eigen::Vector2d>;

double cross(const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
}

// Andrew's monotone chain; strict (collinear boundary points are dropped), counter-clockwise.
Pts convexHull(Pts p) {
  std::sort(p.begin(), p.end(), [](const auto& a, const auto& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  p.erase(std::unique(p.begin(), p.end()), p.end());
  if (p.size() < 3) return p;
  Pts h(2 * p.size());
  std::size_t k = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    while (k >= 2 && cross(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  for (std::size_t i = p.size() - 1, t = k + 1; i-- > 0;) {
    while (k >= t && cross(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  h.resize(k - 1);
  return h;
}

double polygonArea(const Pts& poly) {
  double a = 0;
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const auto& p = poly[i];
    const auto& q = poly[(i + 1) % poly.size()];
    a += p.x() * q.y() - q.x() * p.y();
  }
  return 0.5 * a;
}

// Inside or on the counter-clockwise convex polygon, with a signed-distance margin (px).
bool insideHull(const Pts& hull, const Eigen::Vector2d& q, double margin) {
  for (std::size_t i = 0; i < hull.size(); ++i) {
    const auto& a = hull[i];
    const auto& b = hull[(i + 1) % hull.size()];
    if (cross(a, b, q) / (b - a).norm() < margin) return false;
  }
  return true;
}

double signedArea(const Pts& p, const Triangle2& t) {
  return 0.5 * cross(p[static_cast<std::size_t>(t.v[0])], p[static_cast<std::size_t>(t.v[1])],
                     p[static_cast<std::size_t>(t.v[2])]);
}

Pts randomPoints(int n, unsigned seed, double w = 640, double h = 480) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> ux(0, w), uy(0, h);
  Pts p;
  for (int i = 0; i < n; ++i) p.emplace_back(ux(rng), uy(rng));
  return p;
}

// The checks shared by every point set. `boundary_count` is the number of input points on the
// hull boundary (vertices plus collinear boundary points), for T = 2n - 2 - b.
// `exact_hull` false checks only what holds despite the bug below (no overlap: area and count
// at most those of the hull).
void checkTriangulation(const Pts& pts, const std::vector<Triangle2>& tris, int n_unique,
                        int boundary_count, bool exact_hull = true) {
  const Pts hull = convexHull(pts);
  ASSERT_GE(hull.size(), 3u);
  const double hull_area = polygonArea(hull);
  double sum = 0, min_area = HUGE_VAL;
  for (const auto& t : tris) {
    for (int k = 0; k < 3; ++k) {
      ASSERT_GE(t.v[static_cast<std::size_t>(k)], 0);
      ASSERT_LT(t.v[static_cast<std::size_t>(k)], static_cast<int>(pts.size()));
    }
    const double a = signedArea(pts, t);
    min_area = std::min(min_area, a);
    sum += a;
  }
  EXPECT_GT(min_area, 0.0) << "every triangle counter-clockwise with positive area";
  if (exact_hull) {
    EXPECT_NEAR(sum, hull_area, 1e-9 * hull_area) << "triangles cover exactly the convex hull";
    EXPECT_EQ(static_cast<int>(tris.size()), 2 * n_unique - 2 - boundary_count) << "Euler";
  } else {
    EXPECT_LE(sum, hull_area * (1 + 1e-9)) << "triangles overlap";
    EXPECT_LE(static_cast<int>(tris.size()), 2 * n_unique - 2 - boundary_count);
    EXPECT_GT(sum, 0.99 * hull_area);
  }
  // Empty circumcircle, brute force; tolerance relative to the radius (co-circular points lie
  // on the circle up to rounding).
  int violations = 0;
  for (const auto& t : tris) {
    const auto& a = pts[static_cast<std::size_t>(t.v[0])];
    const auto& b = pts[static_cast<std::size_t>(t.v[1])];
    const auto& c = pts[static_cast<std::size_t>(t.v[2])];
    const double d =
        2 * (a.x() * (b.y() - c.y()) + b.x() * (c.y() - a.y()) + c.x() * (a.y() - b.y()));
    const Eigen::Vector2d cc(
        (a.squaredNorm() * (b.y() - c.y()) + b.squaredNorm() * (c.y() - a.y()) +
         c.squaredNorm() * (a.y() - b.y())) /
            d,
        (a.squaredNorm() * (c.x() - b.x()) + b.squaredNorm() * (a.x() - c.x()) +
         c.squaredNorm() * (b.x() - a.x())) /
            d);
    const double r = (a - cc).norm();
    for (const auto& q : pts)
      if ((q - cc).norm() < r * (1 - 1e-9) - 1e-9) ++violations;
  }
  EXPECT_EQ(violations, 0) << "points strictly inside a circumcircle";
  // No edge is used by more than 2 triangles, and every directed edge at most once.
  std::map<std::pair<int, int>, int> directed;
  for (const auto& t : tris)
    for (int k = 0; k < 3; ++k)
      ++directed[{t.v[static_cast<std::size_t>(k)], t.v[static_cast<std::size_t>((k + 1) % 3)]}];
  int repeated = 0;
  for (const auto& [e, c] : directed) repeated += c > 1 ? 1 : 0;
  EXPECT_EQ(repeated, 0) << "a directed edge appears twice: overlapping triangles";
}

int strictHullSize(const Pts& pts) { return static_cast<int>(convexHull(pts).size()); }

class DelaunayRandom : public ::testing::TestWithParam<int> {};

void checkRandomSets(int n, bool exact_hull) {
  for (unsigned seed : {1u, 2u, 3u}) {
    SCOPED_TRACE("n=" + std::to_string(n) + " seed=" + std::to_string(seed));
    const Pts pts = randomPoints(n, seed * 7919u + static_cast<unsigned>(n));
    Delaunay del;
    std::vector<Triangle2> tris;
    ASSERT_TRUE(del.process(pts, tris).isOk());
    checkTriangulation(pts, tris, n, strictHullSize(pts), exact_hull);
  }
}

// Positive areas, empty circumcircles, no overlap; coverage only bounded (see below).
TEST_P(DelaunayRandom, DelaunayPropertiesAgainstBruteForce) { checkRandomSets(GetParam(), false); }

// BUG (src/features/delaunay.cpp, lines 41-45: the super-triangle vertices at 20 x the point
// span): a hull triangle whose circumcircle is huge (three nearly collinear hull points, common
// for points uniform in a rectangle) contains a super-triangle vertex, so the final
// triangulation lacks it and does not cover the convex hull. Measured on these sets: n = 10
// seed 1 (randomPoints(10, 7929)): 11 triangles instead of 12 (T = 2n - 2 - h), 4.4 px^2 of
// the hull uncovered; n = 100 seed 1: 188 instead of 189 (527 px^2); n = 800: 1578 / 1576 /
// 1586 instead of 1583 / 1578 / 1587 (393 / 157 / 53 px^2). A copy of delaunay.cpp with the
// factor 20 replaced by 1e5 gives the exact counts and areas on all 9 sets, which confirms the
// cause (a robust fix treats the super vertices symbolically, i.e. as points at infinity).
// Effect on the matcher: Delaunay::locate() returns -1 for rejected points in the missing
// triangles near the hull, so they are never recovered.
TEST_P(DelaunayRandom, CoversConvexHullWithEulerCount) {
  checkRandomSets(GetParam(), true);
}

INSTANTIATE_TEST_SUITE_P(Sizes, DelaunayRandom, ::testing::Values(10, 100, 800));

// Points uniform in a disc: the hull is round (no long nearly straight runs), the easy case.
TEST(Delaunay, UniformDisc) {
  std::mt19937 rng(99);
  std::uniform_real_distribution<double> u(-1, 1);
  Pts pts;
  while (pts.size() < 400) {
    const Eigen::Vector2d q(u(rng), u(rng));
    if (q.norm() < 1) pts.push_back(200.0 * q + Eigen::Vector2d(320, 240));
  }
  Delaunay del;
  std::vector<Triangle2> tris;
  ASSERT_TRUE(del.process(pts, tris).isOk());
  checkTriangulation(pts, tris, 400, strictHullSize(pts));
}

// A 12 x 9 integer grid (pitch 10 px): every square has 4 co-circular corners and 38 points
// sit on the hull boundary (4 vertices + collinear ones). T = 2 n - 2 - b = 2 * 11 * 8.
TEST(Delaunay, GridWithCocircularPoints) {
  Pts pts;
  const int nx = 12, ny = 9;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) pts.emplace_back(10.0 * i + 5, 10.0 * j + 7);
  Delaunay del;
  std::vector<Triangle2> tris;
  ASSERT_TRUE(del.process(pts, tris).isOk());
  const int boundary = 2 * (nx + ny) - 4;
  checkTriangulation(pts, tris, nx * ny, boundary);
  EXPECT_EQ(static_cast<int>(tris.size()), 2 * (nx - 1) * (ny - 1));
  // Each triangle is half a grid square: area 50.
  for (const auto& t : tris) EXPECT_NEAR(signedArea(pts, t), 50.0, 1e-9);
}

// Exact duplicates are triangulated once: no triangle refers to a later copy, and the result
// has the triangle count of the unique set.
TEST(Delaunay, DuplicatesAreIgnored) {
  Pts pts = randomPoints(150, 4242);
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> pick(0, 149);
  std::set<int> later;
  for (int k = 0; k < 40; ++k) {
    later.insert(static_cast<int>(pts.size()));
    pts.push_back(pts[static_cast<std::size_t>(pick(rng))]);
  }
  // Also a duplicate placed before its original's later copy in the order.
  Delaunay del;
  std::vector<Triangle2> tris;
  ASSERT_TRUE(del.process(pts, tris).isOk());
  for (const auto& t : tris)
    for (int v : t.v) EXPECT_EQ(later.count(v), 0u) << "triangle uses the later copy " << v;
  checkTriangulation(pts, tris, 150, strictHullSize(pts));
}

TEST(Delaunay, DegenerateInputs) {
  Delaunay del;
  std::vector<Triangle2> tris{{{0, 1, 2}}};
  ASSERT_TRUE(del.process({}, tris).isOk());
  EXPECT_TRUE(tris.empty());
  ASSERT_TRUE(del.process({{0, 0}, {1, 1}}, tris).isOk());
  EXPECT_TRUE(tris.empty());
  // Collinear points: no triangle of positive area exists.
  ASSERT_TRUE(del.process({{0, 0}, {1, 1}, {2, 2}, {3, 3}}, tris).isOk());
  EXPECT_TRUE(tris.empty());
  // A single triangle.
  const Pts three{{0, 0}, {10, 0}, {0, 10}};
  ASSERT_TRUE(del.process(three, tris).isOk());
  ASSERT_EQ(tris.size(), 1u);
  EXPECT_NEAR(signedArea(three, tris[0]), 50.0, 1e-12);
  EXPECT_FALSE(del.process({{0, 0}, {1, 0}, {0, NAN}}, tris).isOk());
}

TEST(Delaunay, LocateInsideAndOutside) {
  const Pts pts = randomPoints(200, 77);
  Delaunay del;
  std::vector<Triangle2> tris;
  ASSERT_TRUE(del.process(pts, tris).isOk());
  const Pts hull = convexHull(pts);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> ux(-50, 690), uy(-50, 530);
  int inside = 0, outside = 0;
  for (int k = 0; k < 3000; ++k) {
    const Eigen::Vector2d q(ux(rng), uy(rng));
    Eigen::Vector3d bary;
    const int t = Delaunay::locate(pts, tris, q, bary);
    if (insideHull(hull, q, 1e-6)) {
      ++inside;
      ASSERT_GE(t, 0) << "query inside the hull " << q.transpose();
      const auto& tri = tris[static_cast<std::size_t>(t)];
      const auto& a = pts[static_cast<std::size_t>(tri.v[0])];
      const auto& b = pts[static_cast<std::size_t>(tri.v[1])];
      const auto& c = pts[static_cast<std::size_t>(tri.v[2])];
      // Independent containment test: q on the left of (or on) every edge.
      EXPECT_GE(cross(a, b, q), -1e-6);
      EXPECT_GE(cross(b, c, q), -1e-6);
      EXPECT_GE(cross(c, a, q), -1e-6);
      EXPECT_NEAR(bary.sum(), 1.0, 1e-9);
      EXPECT_LT((bary[0] * a + bary[1] * b + bary[2] * c - q).norm(), 1e-6);
    } else if (!insideHull(hull, q, -1e-6)) {
      ++outside;
      EXPECT_EQ(t, -1) << "query outside the hull " << q.transpose();
    }
  }
  EXPECT_GT(inside, 1000);
  EXPECT_GT(outside, 300);
  // The vertices themselves are located (barycentric coordinate 1 at that vertex).
  for (std::size_t i = 0; i < pts.size(); i += 17) {
    Eigen::Vector3d bary;
    const int t = Delaunay::locate(pts, tris, pts[i], bary);
    ASSERT_GE(t, 0);
    EXPECT_NEAR(bary.maxCoeff(), 1.0, 1e-9);
  }
}

}  // namespace
}  // namespace svslam
