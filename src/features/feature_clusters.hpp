#pragma once
// Clustered-feature regions of interest (seed 004 sec 3.6): the 3D points of the matched corners
// of one frame are grouped by complete-link agglomerative clustering; each cluster (centre +
// farthest point) is projected into the next stereo pair to give a left and a right search
// region, and the image cells no region touches are marked unknown (searched with lowered
// thresholds by the detector).
//
// Frames and units: points are in the left camera frame of the frame they were measured in
// ("prev"), metres, x right, y down, z forward. Pixels (u, v) of the rectified left image of the
// next frame ("cur"); the right camera sits at +baseline_m along x, so u_right = u - f b / z.
//
// Clustering. d(i, j) = |p_i - p_j| (computed in double, stored rounded to float). The
// complete-link distance of clusters A, B is D(A, B) = max_{a in A, b in B} d(a, b). Starting
// from singletons, the pair with the smallest D is merged while that D <= stop_distance_m. So,
// on return, every cluster's diameter (largest member pair distance) is <= stop_distance_m and
// every two clusters have D > stop_distance_m. Complete link obeys the Lance-Williams update
// D(K, I u J) = max(D(K, I), D(K, J)) and is reducible (D(K, I u J) >= min(D(K, I), D(K, J))),
// so the nearest-neighbour-chain algorithm reproduces the greedy merge sequence exactly (for
// distinct distances) in O(n^2) time over an n x n float matrix preallocated for max_points.
// A cluster whose nearest neighbour is farther than stop_distance_m can never merge again and
// leaves the search at once. Equal distances go to the previous chain element, then to the
// lowest index (with ties the greedy order itself is ambiguous).
//
// Projection. With c, f the centre and farthest point moved into the current frame
// (x_cur = T_cur_prev x_prev) and pi(x) = (f x/z + cx, f y/z + cy), the left ROI is the square
// [u_c - R, u_c + R] x [v_c - R, v_c + R] around pi(c) (the bounding box of the circle of radius
// R), and the right ROI is the same square shifted left by the centre disparity d_c = f b / z_c.
// R = roi_margin_px + (by RoiRadius)
//   kFarthestPoint: |pi(f) - pi(c)|  (the seed's rule; can miss members when the farthest point
//                   lies near the line of sight through c),
//   kSphereBound:   f r max(|c|, |c - b e_x|) / (z_c (z_c - r)), r = |f - c| the cluster radius:
//                   pi(p) - pi(c) = f M (p - c) / (z_c z_p) with M = [z_c 0 -x_c; 0 z_c -y_c],
//                   whose operator norm is |c|; with |p - c| <= r and z_p >= z_c - r this gives
//                   |pi(p) - pi(c)| <= f r |c| / (z_c (z_c - r)), and the same with c - b e_x
//                   for the right camera; so both ROIs hold every member, whatever its depth.
// If the bound does not exist (kSphereBound: z_c - r < min_depth_m; kFarthestPoint: z_f <
// min_depth_m) the ROIs are the whole images. Clusters whose centre is nearer than min_depth_m
// (behind the camera) or whose left ROI misses the image are dropped.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "core/camera.hpp"
#include "core/status.hpp"

namespace svslam {

enum class RoiRadius { kSphereBound, kFarthestPoint };

struct FeatureClusterParams {
  // Merging stops once the smallest complete-link distance is larger, metres, > 0.
  double stop_distance_m = 0.3;
  int min_cluster_size = 2;  // smaller clusters are not returned, >= 1
  // Workspace size, 1..4096 (the distance matrix takes 4 max_points^2 bytes). Larger inputs of
  // n points are subsampled to the points floor(k n / max_points), k = 0..max_points-1.
  int max_points = 1500;
  double roi_margin_px = 8.0;  // added to every ROI radius, px, 0..1000
  RoiRadius roi_radius = RoiRadius::kSphereBound;
  double min_depth_m = 0.1;  // clusters whose centre is nearer are dropped, metres, > 0
  int unknown_cell_px = 32;  // side of the unknown-region grid cells, px, 4..1024
  Status validate() const;
};

struct Cluster {
  Eigen::Vector3d centre_m = Eigen::Vector3d::Zero();    // mean of the members, prev frame
  Eigen::Vector3d farthest_m = Eigen::Vector3d::Zero();  // member farthest from the centre
  double radius_m = 0;                                   // |farthest_m - centre_m|
  double diameter_m = 0;     // largest member pair distance (= the last merge's D; 0 if single)
  float mean_quality = 0;    // mean of the members' quality values (0 if none was given)
  std::vector<int> members;  // indices into process()'s input, ascending
};

// Pixel rectangle [x0, x1) x [y0, y1) of integer pixel coordinates, clipped to the image;
// a point (u, v) is inside when x0 <= u < x1 and y0 <= v < y1. Empty when x0 >= x1 or y0 >= y1.
struct RoiRect {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  bool empty() const { return x0 >= x1 || y0 >= y1; }
  bool contains(double u, double v) const { return u >= x0 && u < x1 && v >= y0 && v < y1; }
};

struct ClusterRoi {
  int cluster = -1;                                     // index into project()'s clusters
  Eigen::Vector2d centre_px = Eigen::Vector2d::Zero();  // pi(c) in the current left image
  double radius_px = 0;      // R (including the margin); unused when whole_image
  double disparity_px = 0;   // d_c = f b / z_c
  bool whole_image = false;  // no bound: both ROIs are the whole image
  RoiRect left;              // never empty
  RoiRect right;             // left shifted by -d_c before clipping; may be empty
};

struct RoiSet {
  std::vector<ClusterRoi> rois;
  int width = 0, height = 0;  // image size, px
  int cell_px = 0;            // unknown-grid cell side; cell (i, j) covers pixels
  int cols = 0, rows = 0;     // [i cell_px, (i+1) cell_px) x [j cell_px, (j+1) cell_px) in image
  std::vector<std::uint8_t> unknown;  // rows x cols, row-major; 1 = no left ROI overlaps it

  bool insideAnyRoi(double u, double v) const;       // in some left ROI
  bool insideAnyRightRoi(double u, double v) const;  // in some right ROI
  bool unknownCell(int col, int row) const {
    return unknown[static_cast<std::size_t>(row * cols + col)] != 0;
  }
  // Whether pixel (u, v) of the left image lies in an unknown cell (false outside the image).
  bool isUnknown(double u, double v) const;
};

class FeatureClusters {
 public:
  explicit FeatureClusters(const FeatureClusterParams& params);
  const Status& initStatus() const { return init_status_; }
  const FeatureClusterParams& params() const { return params_; }

  // Clusters `points` (prev camera frame, metres, finite). `quality` holds one value per point
  // (e.g. corner response or depth sigma) or is empty. Output clusters are ordered by their
  // smallest member index; `out`'s elements are reused, so nothing is allocated once warm.
  Status process(const std::vector<Eigen::Vector3d>& points, const std::vector<float>& quality,
                 std::vector<Cluster>& out);

  // Projects `clusters` into the current stereo pair (see the header comment). The unknown
  // grid covers calib.width x calib.height.
  Status project(const std::vector<Cluster>& clusters, const Eigen::Isometry3d& T_cur_prev,
                 const StereoCalibration& calib, RoiSet& out) const;

 private:
  void merge(int a, int b);
  void closeCluster(int a);
  float& dist(int i, int j) { return dist_[static_cast<std::size_t>(i) * n_ + j]; }

  FeatureClusterParams params_;
  Status init_status_;
  int n_ = 0;                        // points in the current call
  std::vector<float> dist_;          // n_ x n_ complete-link distances between live clusters
  std::vector<int> index_;           // local point -> input index (subsampling)
  std::vector<int> open_;            // clusters that may still merge
  std::vector<int> open_pos_;        // cluster -> position in open_, -1 when closed or merged
  std::vector<int> chain_;           // nearest-neighbour chain
  std::vector<std::uint8_t> alive_;  // cluster representative (smallest local member)
  std::vector<float> height_;        // last merge distance of each representative
  std::vector<int> next_, tail_;     // member lists: next local member, last member of a cluster
  std::vector<int> label_;           // local point -> output cluster, -1 when dropped
  std::vector<double> xyz_;          // subsampled points, x then y then z (structure of arrays)
  std::vector<double> sq_;           // one row of distances in double
  std::vector<double> qsum_;         // quality sum of each output cluster
};

}  // namespace svslam
