#include "loop/loop_closer.hpp"

#include <algorithm>
#include <cmath>

#include "loop/relative_pose.hpp"

namespace svslam {

Status LoopCloserParams::validate() const {
  if (Status s = keyframe.validate(); !s) return s;
  if (Status s = place.validate(); !s) return s;
  if (Status s = verify.validate(); !s) return s;
  if (Status s = consistency.validate(); !s) return s;
  if (Status s = graph.validate(); !s) return s;
  if (min_consistent_loops < 1)
    return Status::invalidArgument("loop.min_consistent_loops must be >= 1");
  if (max_pcm_candidates < 2 || max_pcm_candidates > 1000)
    return Status::invalidArgument("loop.max_pcm_candidates must be in 2..1000");
  if (!(gap_rot_sigma_rad > 0) || !std::isfinite(gap_rot_sigma_rad) ||
      !(gap_trans_sigma_m > 0) || !std::isfinite(gap_trans_sigma_m))
    return Status::invalidArgument("loop.gap_rot_sigma_rad and _trans_m must be > 0");
  if (!(wrong_loop_fraction >= 0 && wrong_loop_fraction <= 0.5))
    return Status::invalidArgument("loop.wrong_loop_fraction must be in [0, 0.5]");
  if (!(filter_edge_chi2 >= 0) || !std::isfinite(filter_edge_chi2))
    return Status::invalidArgument("loop.filter_edge_chi2 must be >= 0");
  if (solve_every_keyframes < 1)
    return Status::invalidArgument("loop.solve_every_keyframes must be >= 1");
  if (max_solve_keyframes < 0)
    return Status::invalidArgument("loop.max_solve_keyframes must be >= 0");
  if (!(odometry_floor_rot_rad > 0) || !std::isfinite(odometry_floor_rot_rad) ||
      !(odometry_floor_trans_m > 0) || !std::isfinite(odometry_floor_trans_m))
    return Status::invalidArgument("loop.odometry_floor_rot_rad and _trans_m must be > 0");
  return Status::ok();
}

LoopFrontEnd::LoopFrontEnd(const LoopCloserParams& params, const StereoCalibration& calib)
    : params_(params), selector_(params.keyframe), builder_(params.keyframe, calib) {
  init_status_ = params.validate();
  if (init_status_) init_status_ = builder_.initStatus();
}

Status LoopFrontEnd::process(const LoopFrameInput& in, bool& made, Keyframe& kf,
                             Matrix6d& odo_cov, Eigen::Isometry3d& odo_T_prev_kf) {
  made = false;
  if (!init_status_) return init_status_;
  if (!in.T_world_cam.matrix().allFinite())
    return Status::invalidArgument("loop front end: non-finite pose");
  if (in.world_epoch < world_epoch_)
    return Status::invalidArgument("loop front end: the world epoch went back");
  const bool new_world = in.world_epoch != world_epoch_;
  if (new_world) {
    world_epoch_ = in.world_epoch;
    world_since_t_ns_ = in.t_ns;
    selector_.reset();  // the next frame with points is the new world's first keyframe
  }
  // Chain this frame's motion onto T_kf_frame (see the header).
  if (next_id_ > 0) {
    Eigen::Isometry3d D;  // T_prev_cur
    Matrix6d C_D;
    if (new_world) {  // between two worlds: no information
      D = T_world_last_.inverse() * in.T_world_cam;
      C_D.setZero();
      C_D.diagonal().head<3>().setConstant(kResetRotSigmaRad * kResetRotSigmaRad);
      C_D.diagonal().tail<3>().setConstant(kResetTransSigmaM * kResetTransSigmaM);
    } else if (in.motion_valid && in.frame == last_frame_ + 1 && in.motion_cov.allFinite() &&
        in.T_cur_prev.matrix().allFinite()) {
      D = in.T_cur_prev.inverse();
      const Matrix6d J = inverseJacobian(in.T_cur_prev);
      C_D = J * in.motion_cov * J.transpose();
    } else {  // no motion estimate, or frames skipped: the online estimate's relative pose
      D = T_world_last_.inverse() * in.T_world_cam;
      C_D.setZero();
      C_D.diagonal().head<3>().setConstant(params_.gap_rot_sigma_rad * params_.gap_rot_sigma_rad);
      C_D.diagonal().tail<3>().setConstant(params_.gap_trans_sigma_m * params_.gap_trans_sigma_m);
    }
    std::vector<Eigen::Isometry3d> f{T_kf_frame_, D};
    std::vector<Matrix6d> A;
    T_kf_frame_ = productJacobians(f, A);
    C_kf_frame_ = A[0] * C_kf_frame_ * A[0].transpose() + A[1] * C_D * A[1].transpose();
  }
  last_frame_ = in.frame;
  T_world_last_ = in.T_world_cam;
  if (!selector_.isKeyframe(in.T_world_cam) || in.dense == nullptr) return Status::ok();
  kf.id = next_id_;
  kf.frame = in.frame;
  kf.t_ns = in.t_ns;
  kf.world_epoch = world_epoch_;
  kf.world_since_t_ns = world_since_t_ns_;
  kf.T_world_cam = in.T_world_cam;
  kf.pose_cov = in.pose_cov;
  const Status s = builder_.process(in.left, *in.dense, kf);
  if (!s) {
    if (s.code() == StatusCode::kFailedPrecondition) return Status::ok();  // too few points
    return s;
  }
  odo_cov = C_kf_frame_;
  odo_T_prev_kf = T_kf_frame_;
  if (next_id_ > 0) {
    odo_cov.topLeftCorner<3, 3>().diagonal().array() +=
        params_.odometry_floor_rot_rad * params_.odometry_floor_rot_rad;
    odo_cov.bottomRightCorner<3, 3>().diagonal().array() +=
        params_.odometry_floor_trans_m * params_.odometry_floor_trans_m;
    odo_cov = 0.5 * (odo_cov + odo_cov.transpose()).eval();
  }
  selector_.accept(in.T_world_cam, kf.median_depth_m);
  T_kf_frame_.setIdentity();
  C_kf_frame_.setZero();
  ++next_id_;
  made = true;
  return Status::ok();
}

LoopCloser::LoopCloser(const LoopCloserParams& params, const BinaryVocabulary& vocabulary)
    : params_(params),
      vocabulary_(vocabulary),
      places_(params.place, 0, static_cast<std::size_t>(vocabulary.numWords())),
      verifier_(params.verify),
      consistency_(params.consistency),
      graph_(params.graph),
      wrong_rng_(params.wrong_loop_seed) {
  init_status_ = params.validate();
  if (init_status_) init_status_ = places_.initStatus();
  if (init_status_) init_status_ = verifier_.initStatus();
  if (init_status_) init_status_ = consistency_.initStatus();
  if (init_status_) init_status_ = graph_.initStatus();
  if (init_status_ && vocabulary.numWords() < 2)
    init_status_ = Status::invalidArgument("loop closing: the vocabulary has no words");
}

std::size_t LoopCloser::memoryBytes() const {
  std::size_t b = places_.memoryBytes();
  for (const Keyframe& k : keyframes_) b += k.bytes();
  b += (T_online_.capacity() + T_corrected_.capacity()) * sizeof(Eigen::Isometry3d) +
       odo_cov_.capacity() * sizeof(Matrix6d);
  return b;
}

Status LoopCloser::process(Keyframe&& kf, const Matrix6d& odo_cov,
                           const Eigen::Isometry3d& odo_T_prev_kf, bool& optimised) {
  optimised = false;
  if (!init_status_) return init_status_;
  if (kf.id != static_cast<int>(keyframes_.size()))
    return Status::invalidArgument("loop closer: keyframe ids must be 0, 1, 2, ... in order");
  if (kf.id > 0 && !isValidCovariance(odo_cov))
    return Status::invalidArgument("loop closer: odometry covariance not positive definite");
  vocabulary_.transform(kf.descriptors, kf.bow);
  const int id = kf.id;
  if (id > 0) {
    // The edge: the filter's relative pose unless it disagrees with the motion chain.
    const Eigen::Isometry3d filter_rel = T_online_.back().inverse() * kf.T_world_cam;
    const Vector6d r =
        relativePoseResidual(Eigen::Isometry3d::Identity(), filter_rel, odo_T_prev_kf);
    const double chi2 = r.dot(odo_cov.ldlt().solve(r));
    const bool chain = !(chi2 < params_.filter_edge_chi2);
    stats_.chain_edges += chain ? 1 : 0;
    chain_edge_.push_back(chain ? 1 : 0);
    const Eigen::Isometry3d edge = chain ? odo_T_prev_kf : filter_rel;
    odo_cov_.push_back(odo_cov);
    odo_T_.push_back(edge);
    T_chain_.push_back(T_chain_.back() * edge);
  } else {
    T_chain_.push_back(kf.T_world_cam);
  }
  T_online_.push_back(kf.T_world_cam);
  const bool new_world = id > 0 && kf.world_epoch != keyframes_.back().world_epoch;
  if (id > 0 && kf.world_epoch < keyframes_.back().world_epoch)
    return Status::invalidArgument("loop closer: the world epoch went back");
  if (new_world) {
    gauge_ = id;
    ++stats_.world_resets;
  }
  // Before any solution the online estimate; after one, chained onto the last corrected
  // keyframe by the motion chain until the next solution; a new world's first keyframe is its
  // gauge: where the online estimate puts it.
  T_corrected_.push_back(id == 0 || !solved_ || new_world
                             ? kf.T_world_cam
                             : Eigen::Isometry3d(T_corrected_.back() * odo_T_.back()));
  keyframes_.push_back(std::move(kf));
  const Keyframe& q = keyframes_.back();
  ++stats_.keyframes;

  if (Status s = places_.query(q.bow, id, candidates_); !s) return s;
  if (places_.lastQueryStats().skipped) ++stats_.queries_skipped;
  if (Status s = places_.add(id, q.bow); !s) return s;
  bool new_verified = false;
  for (const PlaceCandidate& c : candidates_) {
    ++stats_.candidates;
    LoopConstraint lc;
    if (Status s = verifier_.process(q, keyframes_[static_cast<std::size_t>(c.keyframe_id)], lc);
        !s)
      return s;
    if (!lc.accepted) {
      ++stats_.rejected_verification;
      continue;
    }
    ++stats_.verified;
    injectWrongLoop(id, lc);
    verified_.push_back(lc);
    new_verified = true;
    break;  // one constraint per query: the best verified candidate of the island
  }
  if (static_cast<int>(verified_.size()) > params_.max_pcm_candidates)
    verified_.erase(verified_.begin());
  if (!new_verified) return Status::ok();
  bool changed = false;
  if (Status s = runConsistency(changed); !s) return s;
  pending_ = pending_ || changed;
  if (!pending_) return Status::ok();
  if (solved_ && static_cast<int>(keyframes_.size()) - solved_keyframes_ < params_.solve_every_keyframes)
    return Status::ok();
  if (Status s = optimise(); !s) return s;
  optimised = true;
  return Status::ok();
}

Status LoopCloser::finish(bool& optimised) {
  optimised = false;
  if (!init_status_ || !pending_) return init_status_;
  if (Status s = optimise(); !s) return s;
  optimised = true;
  return Status::ok();
}

void LoopCloser::injectWrongLoop(int query, LoopConstraint& lc) {
  if (params_.wrong_loop_fraction <= 0) return;
  std::uniform_real_distribution<double> u(0.0, 1.0);
  if (u(wrong_rng_) >= params_.wrong_loop_fraction) return;
  const int last = query - params_.place.exclude_recent - 1;  // last keyframe a query may return
  if (last < 1) return;
  std::uniform_int_distribution<int> pick(0, last - 1);
  int wrong = pick(wrong_rng_);
  if (wrong >= lc.candidate) ++wrong;  // any keyframe in 0..last but the verified one
  lc.candidate = wrong;
  injected_.emplace_back(lc.query, lc.candidate);
  ++stats_.injected_wrong;
}

Status LoopCloser::runConsistency(bool& changed) {
  changed = false;
  if (keyframes_.size() < 2) return Status::ok();
  // The PCM set: every accepted constraint, then the verified ones not yet accepted.
  std::vector<LoopConstraint> set = accepted_constraints_;
  for (const LoopConstraint& v : verified_) {
    const bool known = std::any_of(set.begin(), set.end(), [&](const LoopConstraint& a) {
      return a.query == v.query && a.candidate == v.candidate;
    });
    if (!known) set.push_back(v);
  }
  std::vector<LoopCandidateEdge> edges;
  edges.reserve(set.size());
  for (const LoopConstraint& c : set) {
    LoopCandidateEdge e;
    e.from = c.query;
    e.to = c.candidate;
    e.T_from_to = c.T_query_candidate;
    e.covariance = c.covariance;
    edges.push_back(e);
  }
  LoopConsistencyResult r;
  if (Status s = consistency_.process(T_chain_, odo_cov_, edges, r); !s) return s;
  int rejected = 0;
  for (LoopDecision d : r.decision) rejected += d != LoopDecision::kAccepted;
  stats_.rejected_consistency = rejected;
  if (static_cast<int>(r.clique.size()) < params_.min_consistent_loops) return Status::ok();
  for (int i : r.clique) {
    if (r.decision[static_cast<std::size_t>(i)] != LoopDecision::kAccepted) continue;
    if (static_cast<std::size_t>(i) < accepted_constraints_.size()) continue;  // already in
    accepted_constraints_.push_back(set[static_cast<std::size_t>(i)]);
    AcceptedLoop a;
    a.query = set[static_cast<std::size_t>(i)].query;
    a.candidate = set[static_cast<std::size_t>(i)].candidate;
    a.inliers = set[static_cast<std::size_t>(i)].inliers;
    a.T_query_candidate = set[static_cast<std::size_t>(i)].T_query_candidate;
    a.covariance = set[static_cast<std::size_t>(i)].covariance;
    a.query_frame = keyframes_[static_cast<std::size_t>(a.query)].frame;
    a.candidate_frame = keyframes_[static_cast<std::size_t>(a.candidate)].frame;
    a.injected = std::find(injected_.begin(), injected_.end(),
                           std::make_pair(a.query, a.candidate)) != injected_.end();
    stats_.injected_wrong_accepted += a.injected;
    accepted_.push_back(a);
    changed = true;
  }
  stats_.accepted = static_cast<int>(accepted_.size());
  return Status::ok();
}

Status LoopCloser::optimise() {
  const std::vector<Eigen::Isometry3d> before = T_corrected_;
  std::vector<Eigen::Isometry3d> poses = before;
  std::vector<PoseGraphEdge> edges;
  edges.reserve(odo_cov_.size() + accepted_constraints_.size());
  for (std::size_t k = 0; k + 1 < T_online_.size(); ++k) {
    PoseGraphEdge e;
    e.from = static_cast<int>(k);
    e.to = static_cast<int>(k + 1);
    e.T_from_to = odo_T_[k];
    e.covariance = odo_cov_[k];
    edges.push_back(e);
  }
  for (const LoopConstraint& c : accepted_constraints_) {
    PoseGraphEdge e;
    e.from = c.query;
    e.to = c.candidate;
    e.T_from_to = c.T_query_candidate;
    e.covariance = c.covariance;
    e.loop = true;
    edges.push_back(e);
  }
  PoseGraphReport rep;
  const int n = static_cast<int>(poses.size());
  const int first_free =
      params_.max_solve_keyframes > 0 ? std::max(0, n - params_.max_solve_keyframes) : 0;
  if (Status s = graph_.optimize(poses, edges, gauge_, rep, first_free); !s) return s;
  T_corrected_ = poses;
  solved_ = true;
  pending_ = false;
  solved_keyframes_ = static_cast<int>(poses.size());
  ++stats_.optimisations;
  stats_.last_optimisation_keyframes = static_cast<int>(poses.size());
  double max_m = 0;
  for (std::size_t k = 0; k < poses.size(); ++k)
    max_m = std::max(max_m, (poses[k].translation() - before[k].translation()).norm());
  stats_.last_max_correction_m = max_m;
  for (std::size_t i = 0; i < accepted_.size() && i < rep.loop_chi2.size(); ++i)
    accepted_[i].chi2_after = rep.loop_chi2[i];
  return Status::ok();
}

Eigen::Isometry3d LoopCloser::correctionAt(std::int64_t t_ns) const {
  if (!solved_ || keyframes_.empty()) return Eigen::Isometry3d::Identity();
  const std::vector<Eigen::Isometry3d>& cor = T_corrected_;
  auto corr = [&](std::size_t k) { return Eigen::Isometry3d(cor[k] * T_online_[k].inverse()); };
  // The last keyframe at or before `frame`.
  auto it = std::upper_bound(keyframes_.begin(), keyframes_.end(), t_ns,
                             [](std::int64_t t, const Keyframe& kf) { return t < kf.t_ns; });
  const std::size_t k =
      it == keyframes_.begin() ? 0 : static_cast<std::size_t>(it - keyframes_.begin()) - 1;
  if (k + 1 >= keyframes_.size() || keyframes_[k].t_ns >= t_ns) return corr(k);
  if (keyframes_[k + 1].world_epoch != keyframes_[k].world_epoch)  // a reset in between
    return t_ns >= keyframes_[k + 1].world_since_t_ns ? corr(k + 1) : corr(k);
  const double a = static_cast<double>(t_ns - keyframes_[k].t_ns) /
                   static_cast<double>(keyframes_[k + 1].t_ns - keyframes_[k].t_ns);
  const Eigen::Isometry3d c0 = corr(k), c1 = corr(k + 1);
  Eigen::Isometry3d c = Eigen::Isometry3d::Identity();
  c.linear() = Eigen::Quaterniond(c0.linear())
                   .slerp(a, Eigen::Quaterniond(c1.linear()))
                   .normalized()
                   .toRotationMatrix();
  c.translation() = (1 - a) * c0.translation() + a * c1.translation();
  return c;
}

}  // namespace svslam
