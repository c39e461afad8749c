#pragma once
// Loop-closure outlier rejection by pairwise consistency maximisation (PCM, Mangelson, Everett
// and Olson, ICRA 2018) against the odometry chain. Pure Eigen (no Ceres), no allocation
// guarantees (it runs once per loop-closing attempt, not per frame).
//
// Inputs. Odometry keyframe poses T_world_kf[k] (k = 0 .. N-1, the online estimate) and, per
// consecutive pair, the covariance odo_cov[k] of the relative pose E_k = T_k_(k+1) =
// T_world_k^-1 T_world_(k+1) (convention of loop/relative_pose.hpp: left perturbation,
// [dtheta, dt] in frame k). The edges are taken as independent. Loop candidates Z_i = T_from_to
// with their 6x6 covariance (same convention, in frame `from`).
//
// Odometry uncertainty of any relative pose. Perturbing every edge, T_world_k = T_world_0 E_0
// ... E_(k-1) moves (left perturbation, world axes) by
//     d_k = L(t_k) s_k,   s_k = sum_(e<k) B_e d_e,   L(t) = [ I 0 ; -[t]x I ],
//     B_e = [ R_e 0 ; [t_(e+1)]x R_e  R_e ]   (R_e, t_e: rotation and position of T_world_e),
// (the product Jacobians of relative_pose.hpp with T_world_0 held fixed), and a relative pose
// T_x_y = T_world_x^-1 T_world_y (any x, y) by
//     d_xy = D_x^T L(t_y) (s_y - s_x),   D_x = diag(R_x, R_x).
// The s_k are cumulative sums of independent terms: Cov(s_k, s_m) = Q_min(k,m) with the prefix
// sums Q_k = sum_(e<k) B_e odo_cov[e] B_e^T, so every covariance below costs O(1) once the Q_k
// are built (O(N)). Positions are taken relative to their mean first (the formulas only depend
// on position differences; this keeps the prefix sums well conditioned).
//
// (a) Single-loop gate: r_i = relativePoseResidual(T_world_from, T_world_to, Z_i) (the loop
//     against the odometry's prediction), C = Cov(d_from,to) + Z_i's covariance (to first order
//     r moves by d_from,to - d_Z), chi2 = r^T C^-1 r. Rejected when chi2 > single_chi2.
// (b) Pairwise: loops i (a_i -> b_i) and j (a_j -> b_j) are consistent when the cycle
//     F = T_odo(a_i -> a_j) Z_j T_odo(b_j -> b_i) Z_i^-1 closes: e = [log R_F ; t_F], with the
//     covariance C = sum_(p,q) M_p Q_min(p,q) M_q^T (p, q over the four endpoints; M the chain
//     rule of the product Jacobians of F through d_a_i,a_j and d_b_j,b_i above, which handles
//     shared and overlapping odometry exactly) + A_2 C_j A_2^T + A_4 J_inv C_i J_inv^T A_4^T, and
//     e^T C^-1 e < pair_chi2. The linearisation of log at e = 0 is used (first order about a
//     closed cycle).
// (c) The largest set of mutually consistent candidates among those passing (a): the maximum
//     clique of the consistency graph. Exact (branch and bound on 64-bit masks, greedy-colouring
//     bound) up to 64 vertices; above that a greedy clique (vertices by decreasing degree, each
//     start vertex tried, the largest kept). Ties go to the lexicographically smallest index set
//     (exact) or the first start vertex (greedy), so the result is deterministic.
//     The clique is accepted when its size >= min_clique; with min_clique = 1 a single loop that
//     passes (a) but is consistent with no other is accepted alone (no corroboration).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "core/status.hpp"
#include "slam/pose_jacobians.hpp"

namespace svslam {

struct LoopCandidateEdge {
  int from = 0, to = 0;                                         // keyframe indices, from != to
  Eigen::Isometry3d T_from_to = Eigen::Isometry3d::Identity();  // measured, maps to -> from
  Matrix6d covariance = Matrix6d::Identity();  // [dtheta (rad), dt (m)] in frame `from`
};

struct LoopConsistencyParams {
  // (a) chi2 (6 dof) gate of a loop against the odometry. chi2_6 at 99.9 % is 22.46; the default
  // is ~4.5x that, because the online odometry covariance is usually optimistic and drift large:
  // this gate only removes gross outliers, (b) does the fine work. > 0.
  double single_chi2 = 100.0;
  // (b) chi2 (6 dof) threshold of a cycle; 16.81 = chi2_6 at 99 %. > 0.
  double pair_chi2 = 16.81;
  // (c) smallest clique that is accepted, >= 1.
  int min_clique = 1;
  Status validate() const;
};

enum class LoopDecision : std::uint8_t {
  kAccepted,
  kRejectedSingle,       // failed (a)
  kRejectedPairwise,     // passed (a), not in the maximum clique
  kRejectedSmallClique,  // in the maximum clique, but it has fewer than min_clique members
};

struct LoopConsistencyResult {
  std::vector<LoopDecision> decision;  // per candidate, input order
  std::vector<double> single_chi2;     // per candidate: the (a) statistic
  std::vector<int> clique;             // the maximum clique, ascending candidate indices
  bool clique_exact = true;            // false when the greedy search was used (> 64 vertices)
  // Pair statistic e^T C^-1 e of (b), symmetric, n x n; NaN in the rows and columns of the
  // candidates that failed (a) (not evaluated), 0 on the diagonal of the others.
  Eigen::MatrixXd pair_chi2;
};

class LoopConsistency {
 public:
  explicit LoopConsistency(const LoopConsistencyParams& params);
  const Status& initStatus() const { return init_status_; }
  // Preconditions (else invalidArgument): T_world_kf.size() >= 2, odo_cov.size() ==
  // T_world_kf.size() - 1, finite orthonormal poses, finite symmetric positive-definite
  // covariances, candidates with indices in range and from != to. An empty candidate list is
  // valid (empty result).
  Status process(const std::vector<Eigen::Isometry3d>& T_world_kf,
                 const std::vector<Matrix6d>& odo_cov, const std::vector<LoopCandidateEdge>& loops,
                 LoopConsistencyResult& out);

 private:
  LoopConsistencyParams params_;
  Status init_status_;
  std::vector<Matrix6d> Q_;  // prefix sums Q_k (k = 0 .. N-1)
};

// Maximum clique of an undirected graph given by its symmetric adjacency (adj[i][j] != 0, the
// diagonal ignored). Exact for n <= 64, greedy above (see (c)); `exact` tells which. Ascending
// indices.
std::vector<int> maximumClique(const std::vector<std::vector<std::uint8_t>>& adj, bool& exact);

}  // namespace svslam
