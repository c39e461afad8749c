#pragma once
// Delaunay triangulation of 2D points (Bowyer-Watson): every triangle's circumcircle holds no
// other input point. Used by the stereo matcher's triangulation-based recovery of rejected
// matches (seed 002 sec 2.2.3). Naive cavity search, O(n^2): meant for up to a few thousand
// points.
#include <Eigen/Core>
#include <array>
#include <vector>

#include "core/status.hpp"

namespace svslam {

struct Triangle2 {
  std::array<int, 3> v;  // indices into the input points, counter-clockwise (y down: clockwise)
};

class Delaunay {
 public:
  // Triangulates `pts` (pixels). Exactly duplicated points are triangulated once (the later
  // copies are ignored). `out` is cleared first.
  Status process(const std::vector<Eigen::Vector2d>& pts, std::vector<Triangle2>& out);

  // The triangle of `tris` containing p (barycentric coordinates all >= -eps), or -1;
  // `bary` receives the barycentric coordinates of p in it.
  static int locate(const std::vector<Eigen::Vector2d>& pts, const std::vector<Triangle2>& tris,
                    const Eigen::Vector2d& p, Eigen::Vector3d& bary);

 private:
  struct Work {
    int a, b, c;
    double cx, cy, r2;  // circumcircle
  };
  std::vector<Eigen::Vector2d> p_;  // input + 3 super-triangle vertices
  std::vector<Work> tris_, keep_;
  std::vector<std::array<int, 2>> edges_;
};

}  // namespace svslam
