#include "loop/loop_consistency.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <bit>
#include <limits>
#include <numeric>
#include <string>

#include "loop/relative_pose.hpp"
#include "motion/visual_motion.hpp"

namespace svslam {
namespace {

Matrix6d blockDiag(const Eigen::Matrix3d& R) {
  Matrix6d D = Matrix6d::Zero();
  D.topLeftCorner<3, 3>() = R;
  D.bottomRightCorner<3, 3>() = R;
  return D;
}

// L(t) = [ I 0 ; -[t]x I ].
Matrix6d lowerShift(const Eigen::Vector3d& t) {
  Matrix6d L = Matrix6d::Identity();
  L.bottomLeftCorner<3, 3>() = -hatSO3(t);
  return L;
}

// r^T C^-1 r; infinity when C is not positive definite.
double mahalanobis2(const Vector6d& r, const Matrix6d& C) {
  const Eigen::LLT<Matrix6d> llt(C);
  if (llt.info() != Eigen::Success) return std::numeric_limits<double>::infinity();
  const double d2 = r.dot(llt.solve(r));
  return std::isfinite(d2) && d2 >= 0 ? d2 : std::numeric_limits<double>::infinity();
}

struct CliqueSearch {
  const std::vector<std::uint64_t>& nbr;
  std::uint64_t best = 0;
  int best_size = 0;

  int colourBound(std::uint64_t P) const {
    int colours = 0;
    while (P != 0) {
      ++colours;
      std::uint64_t Q = P;
      while (Q != 0) {
        const int v = std::countr_zero(Q);
        const std::uint64_t bit = std::uint64_t{1} << v;
        Q &= ~bit & ~nbr[v];
        P &= ~bit;
      }
    }
    return colours;
  }

  // Lexicographic depth-first search: C the current clique (every vertex < those of P), P the
  // vertices that extend it.
  void expand(std::uint64_t C, int c_size, std::uint64_t P) {
    if (P == 0) {
      if (c_size > best_size) {
        best = C;
        best_size = c_size;
      }
      return;
    }
    if (c_size + colourBound(P) <= best_size) return;
    while (P != 0) {
      if (c_size + std::popcount(P) <= best_size) return;
      const int v = std::countr_zero(P);
      const std::uint64_t bit = std::uint64_t{1} << v;
      expand(C | bit, c_size + 1, P & nbr[v]);
      P &= ~bit;
    }
  }
};

}  // namespace

std::vector<int> maximumClique(const std::vector<std::vector<std::uint8_t>>& adj, bool& exact) {
  const int n = static_cast<int>(adj.size());
  std::vector<int> clique;
  exact = n <= 64;
  if (n == 0) return clique;
  auto connected = [&](int i, int j) { return i != j && adj[i][j] != 0 && adj[j][i] != 0; };
  if (exact) {
    std::vector<std::uint64_t> nbr(n, 0);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j)
        if (connected(i, j)) nbr[i] |= std::uint64_t{1} << j;
    CliqueSearch search{nbr};
    const std::uint64_t all = n == 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << n) - 1;
    search.expand(0, 0, all);
    for (int i = 0; i < n; ++i)
      if ((search.best >> i) & 1U) clique.push_back(i);
    return clique;
  }
  std::vector<int> degree(n, 0);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) degree[i] += connected(i, j) ? 1 : 0;
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return degree[a] > degree[b]; });
  std::vector<int> current;
  for (const int s : order) {
    if (degree[s] + 1 <= static_cast<int>(clique.size())) break;  // cannot beat the best
    current.assign(1, s);
    for (const int v : order) {
      if (v == s) continue;
      if (std::all_of(current.begin(), current.end(), [&](int u) { return connected(u, v); }))
        current.push_back(v);
    }
    if (current.size() > clique.size()) clique = current;
  }
  std::sort(clique.begin(), clique.end());
  return clique;
}

Status LoopConsistencyParams::validate() const {
  if (!(single_chi2 > 0)) return Status::invalidArgument("single_chi2 must be > 0");
  if (!(pair_chi2 > 0)) return Status::invalidArgument("pair_chi2 must be > 0");
  if (min_clique < 1) return Status::invalidArgument("min_clique must be >= 1");
  return Status::ok();
}

LoopConsistency::LoopConsistency(const LoopConsistencyParams& params) : params_(params) {
  init_status_ = params_.validate();
}

Status LoopConsistency::process(const std::vector<Eigen::Isometry3d>& T_world_kf,
                                const std::vector<Matrix6d>& odo_cov,
                                const std::vector<LoopCandidateEdge>& loops,
                                LoopConsistencyResult& out) {
  if (!init_status_) return init_status_;
  const int N = static_cast<int>(T_world_kf.size());
  if (N < 2) return Status::invalidArgument("loop consistency: fewer than 2 keyframes");
  if (odo_cov.size() + 1 != T_world_kf.size())
    return Status::invalidArgument("loop consistency: odo_cov must have one entry per edge (" +
                                   std::to_string(N - 1) + ")");
  for (int k = 0; k < N; ++k)
    if (!isValidPose(T_world_kf[k]))
      return Status::invalidArgument("loop consistency: keyframe pose " + std::to_string(k) +
                                     " is not finite or not a rotation");
  for (int k = 0; k + 1 < N; ++k)
    if (!isValidCovariance(odo_cov[k]))
      return Status::invalidArgument("loop consistency: odo_cov[" + std::to_string(k) +
                                     "] is not finite symmetric positive definite");
  const int n = static_cast<int>(loops.size());
  for (int i = 0; i < n; ++i) {
    const LoopCandidateEdge& l = loops[i];
    if (l.from < 0 || l.from >= N || l.to < 0 || l.to >= N || l.from == l.to)
      return Status::invalidArgument("loop consistency: candidate " + std::to_string(i) +
                                     " has bad keyframe indices");
    if (!isValidPose(l.T_from_to) || !isValidCovariance(l.covariance))
      return Status::invalidArgument("loop consistency: candidate " + std::to_string(i) +
                                     " has a non-finite pose or a bad covariance");
  }

  // Centred positions and the prefix sums Q_k.
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& T : T_world_kf) mean += T.translation();
  mean /= N;
  auto pos = [&](int k) -> Eigen::Vector3d { return T_world_kf[k].translation() - mean; };
  Q_.resize(N);
  Q_[0].setZero();
  for (int e = 0; e + 1 < N; ++e) {
    const Eigen::Matrix3d& R = T_world_kf[e].linear();
    Matrix6d B = blockDiag(R);
    B.bottomLeftCorner<3, 3>() = hatSO3(pos(e + 1)) * R;
    Q_[e + 1] = Q_[e] + B * odo_cov[e] * B.transpose();
  }
  // M_xy = D_x^T L(t_y): d_xy = M_xy (s_y - s_x).
  auto relJacobian = [&](int x, int y) -> Matrix6d {
    return blockDiag(T_world_kf[x].linear()).transpose() * lowerShift(pos(y));
  };
  auto odo = [&](int x, int y) -> Eigen::Isometry3d {
    return T_world_kf[x].inverse(Eigen::Isometry) * T_world_kf[y];
  };

  out.decision.assign(n, LoopDecision::kRejectedSingle);
  out.single_chi2.assign(n, std::numeric_limits<double>::quiet_NaN());
  out.clique.clear();
  out.clique_exact = true;
  out.pair_chi2.setConstant(n, n, std::numeric_limits<double>::quiet_NaN());

  // (a)
  std::vector<int> survivors;
  for (int i = 0; i < n; ++i) {
    const LoopCandidateEdge& l = loops[i];
    const Vector6d r = relativePoseResidual(T_world_kf[l.from], T_world_kf[l.to], l.T_from_to);
    const Matrix6d M = relJacobian(l.from, l.to);
    const Matrix6d C =
        M * (Q_[std::max(l.from, l.to)] - Q_[std::min(l.from, l.to)]) * M.transpose() +
        l.covariance;
    out.single_chi2[i] = mahalanobis2(r, C);
    if (out.single_chi2[i] <= params_.single_chi2) survivors.push_back(i);
  }

  // (b)
  const int m = static_cast<int>(survivors.size());
  std::vector<std::vector<std::uint8_t>> adj(m, std::vector<std::uint8_t>(m, 0));
  std::vector<Eigen::Isometry3d> factors(4);
  std::vector<Matrix6d> A;
  for (int u = 0; u < m; ++u) {
    const int i = survivors[u];
    out.pair_chi2(i, i) = 0;
    for (int v = u + 1; v < m; ++v) {
      const int j = survivors[v];
      const LoopCandidateEdge& li = loops[i];
      const LoopCandidateEdge& lj = loops[j];
      const Eigen::Isometry3d Zi_inv = li.T_from_to.inverse(Eigen::Isometry);
      factors[0] = odo(li.from, lj.from);
      factors[1] = lj.T_from_to;
      factors[2] = odo(lj.to, li.to);
      factors[3] = Zi_inv;
      const Eigen::Isometry3d F = productJacobians(factors, A);
      Vector6d e;
      e.head<3>() = logSO3(F.linear());
      e.tail<3>() = F.translation();
      // Odometry part: endpoints p with d = sum_p M_p s_p (sum_p M_p = 0).
      const int idx[4] = {li.from, lj.from, lj.to, li.to};
      const Matrix6d M1 = A[0] * relJacobian(li.from, lj.from);
      const Matrix6d M3 = A[2] * relJacobian(lj.to, li.to);
      const Matrix6d Mp[4] = {-M1, M1, -M3, M3};
      const int p0 = *std::min_element(idx, idx + 4);
      Matrix6d C = Matrix6d::Zero();
      for (int p = 0; p < 4; ++p)
        for (int q = 0; q < 4; ++q)
          C += Mp[p] * (Q_[std::min(idx[p], idx[q])] - Q_[p0]) * Mp[q].transpose();
      const Matrix6d A4 = A[3] * inverseJacobian(li.T_from_to);
      C += A[1] * lj.covariance * A[1].transpose() + A4 * li.covariance * A4.transpose();
      const double chi2 = mahalanobis2(e, 0.5 * (C + C.transpose()));
      out.pair_chi2(i, j) = out.pair_chi2(j, i) = chi2;
      if (chi2 < params_.pair_chi2) adj[u][v] = adj[v][u] = 1;
    }
  }

  // (c)
  bool exact = true;
  const std::vector<int> clique = maximumClique(adj, exact);
  out.clique_exact = exact;
  for (const int i : survivors) out.decision[i] = LoopDecision::kRejectedPairwise;
  const bool big_enough = static_cast<int>(clique.size()) >= params_.min_clique;
  for (const int u : clique) {
    out.clique.push_back(survivors[u]);
    out.decision[survivors[u]] =
        big_enough ? LoopDecision::kAccepted : LoopDecision::kRejectedSmallClique;
  }
  return Status::ok();
}

}  // namespace svslam
