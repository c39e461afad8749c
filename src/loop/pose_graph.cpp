#include "loop/pose_graph.hpp"

#include <ceres/ceres.h>
#include <ceres/manifold.h>
#include <ceres/rotation.h>

#include <Eigen/Cholesky>
#include <cmath>
#include <numeric>

namespace svslam {
namespace {

// The whitened residual of one edge (header): parameters q_from, t_from, q_to, t_to.
class RelativePoseCost {
 public:
  RelativePoseCost(const Eigen::Isometry3d& Z_from_to, const Matrix6d& sqrt_info)
      : q_Z_inv_(Eigen::Quaterniond(Z_from_to.linear()).conjugate()),
        t_Z_(Z_from_to.translation()),
        sqrt_info_(sqrt_info) {}

  template <class T>
  bool operator()(const T* q_a_ptr, const T* t_a_ptr, const T* q_b_ptr, const T* t_b_ptr,
                  T* residual_ptr) const {
    const Eigen::Map<const Eigen::Quaternion<T>> q_a(q_a_ptr), q_b(q_b_ptr);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> t_a(t_a_ptr), t_b(t_b_ptr);
    const Eigen::Quaternion<T> q_a_inv = q_a.conjugate();
    const Eigen::Quaternion<T> q_err = q_a_inv * q_b * q_Z_inv_.template cast<T>();
    const T q_wxyz[4] = {q_err.w(), q_err.x(), q_err.y(), q_err.z()};
    Eigen::Matrix<T, 6, 1> r;
    ceres::QuaternionToAngleAxis(q_wxyz, r.data());
    r.template tail<3>() = q_a_inv * (t_b - t_a) - t_Z_.template cast<T>();
    Eigen::Map<Eigen::Matrix<T, 6, 1>> residual(residual_ptr);
    residual = sqrt_info_.template cast<T>() * r;
    return true;
  }

 private:
  Eigen::Quaterniond q_Z_inv_;
  Eigen::Vector3d t_Z_;
  Matrix6d sqrt_info_;
};

// W = L^-1 with C = L L^T.
Matrix6d whitening(const Matrix6d& C) {
  const Eigen::LLT<Matrix6d> llt(C);
  return llt.matrixL().solve(Matrix6d::Identity());
}

int findRoot(std::vector<int>& parent, int i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

}  // namespace

Status PoseGraphParams::validate() const {
  if (max_iterations < 1) return Status::invalidArgument("max_iterations must be >= 1");
  if (!(loop_loss_scale >= 0) || !std::isfinite(loop_loss_scale))
    return Status::invalidArgument("loop_loss_scale must be finite and >= 0");
  if (!(function_tolerance > 0)) return Status::invalidArgument("function_tolerance must be > 0");
  if (num_threads < 1) return Status::invalidArgument("num_threads must be >= 1");
  return Status::ok();
}

PoseGraph::PoseGraph(const PoseGraphParams& params) : params_(params) {
  init_status_ = params_.validate();
}

Status PoseGraph::optimize(std::vector<Eigen::Isometry3d>& T_world_kf,
                           const std::vector<PoseGraphEdge>& edges, int fixed_index,
                           PoseGraphReport& report, int first_free) {
  if (!init_status_) return init_status_;
  const int n = static_cast<int>(T_world_kf.size());
  if (n == 0) return Status::invalidArgument("pose graph: no keyframe pose");
  if (edges.empty()) return Status::invalidArgument("pose graph: no edge");
  if (fixed_index < 0 || fixed_index >= n)
    return Status::invalidArgument("pose graph: fixed_index out of range");
  if (first_free < 0 || first_free >= n)
    return Status::invalidArgument("pose graph: first_free out of range");
  const auto constant = [&](int k) { return k == fixed_index || k < first_free; };
  for (int k = 0; k < n; ++k)
    if (!isValidPose(T_world_kf[k]))
      return Status::invalidArgument("pose graph: pose " + std::to_string(k) +
                                     " is not finite or not a rotation");
  std::vector<int> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  for (std::size_t i = 0; i < edges.size(); ++i) {
    const PoseGraphEdge& e = edges[i];
    if (e.from < 0 || e.from >= n || e.to < 0 || e.to >= n || e.from == e.to)
      return Status::invalidArgument("pose graph: edge " + std::to_string(i) +
                                     " has bad keyframe indices");
    if (!isValidPose(e.T_from_to) || !isValidCovariance(e.covariance))
      return Status::invalidArgument("pose graph: edge " + std::to_string(i) +
                                     " has a non-finite pose or a bad covariance");
    parent[findRoot(parent, e.from)] = findRoot(parent, e.to);
  }
  const int root = findRoot(parent, fixed_index);
  for (int k = 0; k < n; ++k)
    if (findRoot(parent, k) != root)
      return Status::invalidArgument("pose graph: pose " + std::to_string(k) +
                                     " is not connected to the fixed pose");

  quaternions_.resize(4 * static_cast<std::size_t>(n));
  translations_.resize(3 * static_cast<std::size_t>(n));
  for (int k = 0; k < n; ++k) {
    Eigen::Map<Eigen::Quaterniond> q(&quaternions_[4 * k]);
    Eigen::Map<Eigen::Vector3d> t(&translations_[3 * k]);
    q = Eigen::Quaterniond(T_world_kf[k].linear()).normalized();
    t = T_world_kf[k].translation();
  }

  ceres::Problem problem;
  std::vector<Matrix6d> sqrt_info(edges.size());
  for (std::size_t i = 0; i < edges.size(); ++i) {
    const PoseGraphEdge& e = edges[i];
    sqrt_info[i] = whitening(e.covariance);
    if (constant(e.from) && constant(e.to)) continue;  // a constant term
    auto* cost = new ceres::AutoDiffCostFunction<RelativePoseCost, 6, 4, 3, 4, 3>(
        new RelativePoseCost(e.T_from_to, sqrt_info[i]));
    ceres::LossFunction* loss = nullptr;
    if (e.loop && params_.loop_loss_scale > 0)
      loss = new ceres::CauchyLoss(params_.loop_loss_scale);
    problem.AddResidualBlock(cost, loss, &quaternions_[4 * e.from], &translations_[3 * e.from],
                             &quaternions_[4 * e.to], &translations_[3 * e.to]);
  }
  for (int k = 0; k < n; ++k) {
    double* q = &quaternions_[4 * k];
    if (!problem.HasParameterBlock(q)) continue;
    problem.SetManifold(q, new ceres::EigenQuaternionManifold);
  }
  for (int k = 0; k < n; ++k) {
    if (!constant(k) || !problem.HasParameterBlock(&quaternions_[4 * k])) continue;
    problem.SetParameterBlockConstant(&quaternions_[4 * k]);
    problem.SetParameterBlockConstant(&translations_[3 * k]);
  }

  ceres::Solver::Options options;
  options.max_num_iterations = params_.max_iterations;
  options.function_tolerance = params_.function_tolerance;
  options.num_threads = params_.num_threads;
  options.logging_type = ceres::SILENT;
  options.minimizer_progress_to_stdout = false;
  if (ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::SUITE_SPARSE)) {
    options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
    options.sparse_linear_algebra_library_type = ceres::SUITE_SPARSE;
  } else if (ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::EIGEN_SPARSE)) {
    options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
    options.sparse_linear_algebra_library_type = ceres::EIGEN_SPARSE;
  } else if (ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::ACCELERATE_SPARSE)) {
    options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
    options.sparse_linear_algebra_library_type = ceres::ACCELERATE_SPARSE;
  } else {
    options.linear_solver_type = ceres::ITERATIVE_SCHUR;
  }
  std::string why;
  if (!options.IsValid(&why)) return Status(StatusCode::kInternal, "pose graph: " + why);

  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  if (!summary.IsSolutionUsable())
    return Status(StatusCode::kInternal, "pose graph: Ceres failed: " + summary.message);

  for (int k = 0; k < n; ++k) {
    if (constant(k)) continue;  // bit for bit as given
    const Eigen::Quaterniond q =
        Eigen::Map<const Eigen::Quaterniond>(&quaternions_[4 * k]).normalized();
    T_world_kf[k].setIdentity();
    T_world_kf[k].linear() = q.toRotationMatrix();
    T_world_kf[k].translation() = Eigen::Map<const Eigen::Vector3d>(&translations_[3 * k]);
  }
  report.iterations = summary.num_successful_steps + summary.num_unsuccessful_steps;
  report.initial_cost = summary.initial_cost;
  report.final_cost = summary.final_cost;
  report.converged = summary.termination_type == ceres::CONVERGENCE;
  report.message = summary.message;
  report.loop_chi2.clear();
  for (std::size_t i = 0; i < edges.size(); ++i) {
    const PoseGraphEdge& e = edges[i];
    if (!e.loop) continue;
    const Vector6d w =
        sqrt_info[i] * relativePoseResidual(T_world_kf[e.from], T_world_kf[e.to], e.T_from_to);
    report.loop_chi2.push_back(w.squaredNorm());
  }
  return Status::ok();
}

}  // namespace svslam
