#include "pipeline/realtime/loop_stage.hpp"

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <functional>
#include <iterator>
#include <limits>
#include <memory>
#include <utility>

#include "pipeline/cli/json_writer.hpp"
#include "pipeline/realtime/pipeline_runner.hpp"

#ifdef SVSLAM_HAVE_CERES
#include <readerwriterqueue/readerwritercircularbuffer.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <chrono>
#include <condition_variable>
#include <deque>
#include <mutex>

#include "drivers/files/trajectory_io.hpp"
#include "drivers/files/vocabulary_file.hpp"
#include "drivers/lcm/lcm_pose_correction.hpp"
#include "loop/loop_closer.hpp"
#include "loop/relative_pose.hpp"
#include "pipeline/service/scheduling.hpp"
#endif

namespace svslam::rt {

#ifdef SVSLAM_HAVE_CERES

bool loopClosingAvailable() { return true; }

namespace {
struct KeyframeItem {
  Keyframe kf;
  Matrix6d odo_cov = Matrix6d::Zero();
  Eigen::Isometry3d odo_T = Eigen::Isometry3d::Identity();
};
constexpr std::size_t kRingKeyframes = 64;
}  // namespace

struct LoopStage::Impl {
  Impl(const config::RunConfig& c, drivers::StereoSource& s, std::string dir,
       drivers::LcmLink* l)
      : cfg(c), source(s), out_dir(std::move(dir)), lcm(l), ring(kRingKeyframes) {}
  const config::RunConfig& cfg;
  drivers::StereoSource& source;
  std::string out_dir;
  drivers::LcmLink* lcm;
  std::unique_ptr<BinaryVocabulary> vocabulary;
  std::unique_ptr<LoopFrontEnd> front;
  std::unique_ptr<LoopCloser> closer;
  moodycamel::BlockingReaderWriterCircularBuffer<std::unique_ptr<KeyframeItem>> ring;
  std::thread thread;
  bool started = false;
  bool closed = false;
  // Back end (its thread; read after join).
  Status error;
  std::int64_t corrections_published = 0;
  std::vector<Eigen::Isometry3d> last_sent;  // per keyframe, the correction last published
  std::vector<double> solve_ms;
  // Per frame seen (front-end thread; read after the run): its keyframe and motion chain from
  // it, for the optimised trajectory.
  struct FrameLink {
    std::int64_t t_ns;
    int kf;
    int world_epoch;
    Eigen::Quaternionf q;
    Eigen::Vector3f t;
  };
  std::vector<FrameLink> links;
  // First frame of each world after the first and its epoch (front-end thread, the mapper's;
  // read there during the run and after it). An epoch may skip values (resets on frames the
  // front end did not see).
  std::vector<std::pair<std::int64_t, int>> world_starts;
  int lastWorldEpoch() const { return world_starts.empty() ? 0 : world_starts.back().second; }
  // The world a frame was estimated in.
  int worldOf(std::int64_t frame) const {
    const auto it = std::upper_bound(
        world_starts.begin(), world_starts.end(), frame,
        [](std::int64_t f, const std::pair<std::int64_t, int>& w) { return f < w.first; });
    return it == world_starts.begin() ? 0 : std::prev(it)->second;
  }
  // The corrections of the last solution (written by the back end after each solve, read by
  // the mapper during the run and by finish after it): per keyframe its frame, world and
  // correction T_corrected_k T_online_k^-1.
  struct Snapshot {
    std::vector<std::int64_t> frame;
    std::vector<int> world;
    std::vector<Eigen::Isometry3d> C;
    // The keyframe whose correction applies to a frame of `world` whose last keyframe at or
    // before it is k: k itself, or after a reset the new world's first keyframe (-1: none yet).
    int keyframeForWorld(std::size_t k, int w) const {
      if (world[k] == w) return static_cast<int>(k);
      if (k + 1 < world.size() && world[k + 1] == w) return static_cast<int>(k + 1);
      return -1;
    }
  };
  std::mutex snap_mutex;
  std::shared_ptr<const Snapshot> snapshot;
  std::atomic<int> solutions_made{0};
  void takeSnapshot(bool new_solution) {
    auto snap = std::make_shared<Snapshot>();
    const std::vector<Keyframe>& kfs = closer->keyframes();
    snap->frame.reserve(kfs.size());
    snap->world.reserve(kfs.size());
    snap->C.reserve(kfs.size());
    for (std::size_t k = 0; k < kfs.size(); ++k) {
      snap->frame.push_back(kfs[k].frame);
      snap->world.push_back(kfs[k].world_epoch);
      snap->C.push_back(keyframeCorrection(k));
    }
    std::lock_guard<std::mutex> lock(snap_mutex);
    snapshot = std::move(snap);
    if (new_solution) ++solutions_made;
  }
  std::shared_ptr<const Snapshot> latestSnapshot() {
    std::lock_guard<std::mutex> lock(snap_mutex);
    return snapshot;
  }
  double vocabulary_load_ms = 0;
  int vocabulary_words = 0;
  std::int64_t frames_seen = 0;

  // Feedback (see the header): written under fb_mutex by the front end (frames seen, keyframes
  // handed over), the back end (keyframes done, solutions) and the estimator (waits, takes).
  struct Solution {
    std::int64_t kf_frame;
    int world_epoch;      // of the keyframe
    Eigen::Isometry3d C;  // T_corrected_K T_online_K^-1
    Matrix6d cov;         // of T_corrected_K, [dtheta, dt] world frame
  };
  std::mutex fb_mutex;
  std::condition_variable fb_cv;
  std::int64_t last_front = -1;       // last frame the front end handled
  std::deque<std::int64_t> pending;   // frames of the keyframes handed to the back end, not done
  std::int64_t resolved = -1;         // every keyframe of a frame <= this one is done
  bool fb_stop = false;
  bool wait_for_back_end = false;
  std::deque<Solution> solutions;     // posted, not yet taken
  // Estimator thread (read after the run).
  struct Applied {
    std::int64_t frame;
    Eigen::Isometry3d delta;
  };
  std::vector<Applied> applied;
  double feedback_wait_max_ms = 0;
  std::int64_t feedback_wait_timeouts = 0;
  std::int64_t feedback_dropped_other_world = 0;  // solutions of a world before a reset

  void updateResolved() { resolved = pending.empty() ? last_front : pending.front() - 1; }
  // Covariance of the corrected pose of keyframe k through the newest accepted loop (header).
  Matrix6d correctedCovariance(std::size_t k) const;
  // Back end: keyframe done (with a new solution when `optimised`).
  void keyframeDone(bool optimised);
  // The moves of `moves` applied at frames in (after_frame, up_to_frame], composed:
  // Delta_m ... Delta_1.
  static Eigen::Isometry3d appliedBetween(const std::vector<Applied>& moves,
                                          std::int64_t after_frame, std::int64_t up_to_frame);
  // Correction of keyframe k: T_corrected_k T_online_k^-1.
  Eigen::Isometry3d keyframeCorrection(std::size_t k) const {
    return closer->correctedKeyframes()[k] * closer->keyframes()[k].T_world_cam.inverse();
  }
  // LoopStage::frameCorrection (header), from a solution's corrections and the moves applied.
  bool frameCorrection(const Snapshot& snap, const std::vector<Applied>& moves,
                       std::int64_t frame, Eigen::Isometry3d& M) const;
  // The same from the last solution (after the run).
  bool frameCorrection(std::int64_t frame, Eigen::Isometry3d& M) const;
  Status writeLandmarks(const std::vector<MapLandmark>& map) const;

  void backEnd();
  void publishCorrection(const Keyframe& kf);
};

void LoopStage::Impl::keyframeDone(bool optimised) {
  std::lock_guard<std::mutex> lock(fb_mutex);
  if (!pending.empty()) pending.pop_front();
  if (optimised && cfg.loop_feedback && !closer->keyframes().empty()) {
    const std::size_t k = closer->keyframes().size() - 1;
    solutions.push_back({closer->keyframes()[k].frame, closer->keyframes()[k].world_epoch,
                         keyframeCorrection(k), correctedCovariance(k)});
  }
  updateResolved();
  fb_cv.notify_all();
}

Matrix6d LoopStage::Impl::correctedCovariance(std::size_t k) const {
  const std::vector<AcceptedLoop>& loops = closer->acceptedLoops();
  const AcceptedLoop* a = nullptr;
  for (const AcceptedLoop& l : loops)
    if (!a || l.query > a->query) a = &l;
  const std::vector<Keyframe>& kfs = closer->keyframes();
  if (!a || static_cast<std::size_t>(a->query) > k) return kfs[k].pose_cov;
  std::vector<Eigen::Isometry3d> factors{closer->correctedKeyframes()[a->candidate],
                                         a->T_query_candidate.inverse()};
  std::vector<Matrix6d> covs{kfs[a->candidate].pose_cov, Matrix6d::Zero()};
  const Matrix6d J = inverseJacobian(a->T_query_candidate);
  covs[1] = J * a->covariance * J.transpose();
  for (std::size_t e = static_cast<std::size_t>(a->query); e < k; ++e) {
    factors.push_back(closer->odometryEdge(e));
    covs.push_back(closer->odometryCovariance(e));
  }
  std::vector<Matrix6d> A;
  (void)productJacobians(factors, A);
  Matrix6d cov = Matrix6d::Zero();
  for (std::size_t i = 0; i < factors.size(); ++i) cov += A[i] * covs[i] * A[i].transpose();
  return 0.5 * (cov + cov.transpose());
}

Eigen::Isometry3d LoopStage::Impl::appliedBetween(const std::vector<Applied>& moves,
                                                  std::int64_t after_frame,
                                                  std::int64_t up_to_frame) {
  Eigen::Isometry3d B = Eigen::Isometry3d::Identity();
  for (const Applied& a : moves)
    if (a.frame > after_frame && a.frame <= up_to_frame) B = a.delta * B;
  return B;
}

void LoopStage::Impl::backEnd() {
  // The back end is never worth a late pose: like the mapper it yields the cores to the pose
  // path (nice +10 for this thread only).
  service::setCurrentThreadName("svslam-loop");
  (void)setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), 10);
  for (;;) {
    std::unique_ptr<KeyframeItem> item;
    ring.wait_dequeue(item);
    if (!item) {  // end of the run: solve what is pending
      bool optimised = false;
      if (error.isOk()) {
        const std::int64_t t0 = steadyNowNs();
        if (Status s = closer->finish(optimised); !s) error = s;
        // The end state (keyframes since the last solution chained onto it) for finish().
        if (error.isOk() && closer->solved()) takeSnapshot(optimised);
        if (optimised) {
          solve_ms.push_back(static_cast<double>(steadyNowNs() - t0) * 1e-6);
          if (lcm && !closer->keyframes().empty()) publishCorrection(closer->keyframes().back());
        }
      }
      std::lock_guard<std::mutex> lock(fb_mutex);
      fb_stop = true;
      fb_cv.notify_all();
      return;
    }
    bool optimised = false;
    if (error.isOk()) {
      const std::int64_t t_ns = item->kf.t_ns;
      const std::int64_t t0 = steadyNowNs();
      const Status s = closer->process(std::move(item->kf), item->odo_cov, item->odo_T, optimised);
      if (!s) {
        error = Status(s.code(), "loop closing, keyframe at t_ns " + std::to_string(t_ns) + ": " +
                                     s.message());
        optimised = false;
      } else if (optimised) {
        solve_ms.push_back(static_cast<double>(steadyNowNs() - t0) * 1e-6);
        takeSnapshot(true);
        if (lcm) publishCorrection(closer->keyframes().back());
      }
    }
    keyframeDone(optimised);
  }
}

void LoopStage::Impl::publishCorrection(const Keyframe& kf) {
  const std::vector<Keyframe>& kfs = closer->keyframes();
  const std::vector<Eigen::Isometry3d>& cor = closer->correctedKeyframes();
  drivers::PoseCorrectionMessage m;
  m.t_ns = kf.t_ns;
  m.correction_seq = corrections_published;
  m.loops_accepted = static_cast<int>(closer->acceptedLoops().size());
  m.keyframes_total = static_cast<int>(kfs.size());
  last_sent.resize(kfs.size(), Eigen::Isometry3d::Identity());
  for (std::size_t k = 0; k < kfs.size(); ++k) {
    const Eigen::Isometry3d C = cor[k] * kfs[k].T_world_cam.inverse();
    const Eigen::Isometry3d d = last_sent[k].inverse() * C;
    if (d.translation().norm() < 1e-4 && Eigen::AngleAxisd(d.linear()).angle() < 1e-6) continue;
    m.keyframe_t_ns.push_back(kfs[k].t_ns);
    m.correction.push_back(C);
    last_sent[k] = C;
  }
  std::vector<std::uint8_t> bytes;
  for (const drivers::PoseCorrectionMessage& part : drivers::splitPoseCorrection(m)) {
    if (!drivers::encodePoseCorrection(part, bytes)) continue;
    (void)lcm->publishRaw(cfg.lcm.params.correction_channel, bytes.data(), bytes.size());
  }
  ++corrections_published;
}

LoopStage::LoopStage(const config::RunConfig& cfg, drivers::StereoSource& source,
                     std::string out_dir, drivers::LcmLink* lcm)
    : impl_(std::make_unique<Impl>(cfg, source, std::move(out_dir), lcm)) {}

LoopStage::~LoopStage() {
  stopFeedback();
  if (impl_->started && !impl_->closed) {
    impl_->ring.wait_enqueue(nullptr);
    impl_->closed = true;
  }
  if (impl_->thread.joinable()) impl_->thread.join();
}

Status LoopStage::init() {
  Impl& m = *impl_;
  if (m.cfg.loop_vocabulary.empty())
    return Status::invalidArgument(
        "loop.enabled needs loop.vocabulary (a file made by `svslam train-vocabulary`)");
  const std::int64_t t0 = steadyNowNs();
  auto voc = drivers::loadVocabulary(m.cfg.loop_vocabulary);
  if (!voc) return Status(voc.status().code(), "loop.vocabulary: " + voc.status().message());
  m.vocabulary_load_ms = static_cast<double>(steadyNowNs() - t0) * 1e-6;
  m.vocabulary = std::make_unique<BinaryVocabulary>(std::move(*voc));
  m.vocabulary_words = m.vocabulary->numWords();
  LoopCloserParams p = m.cfg.loop;
  p.verify.motion.seed = m.cfg.seed;
  p.wrong_loop_seed = static_cast<std::uint32_t>(m.cfg.seed ^ 0x9e3779b9u);
  m.front = std::make_unique<LoopFrontEnd>(p, m.source.calibration());
  if (Status s = m.front->initStatus(); !s) return s;
  m.closer = std::make_unique<LoopCloser>(p, *m.vocabulary);
  if (Status s = m.closer->initStatus(); !s) return s;
  m.thread = std::thread([&m] { m.backEnd(); });
  m.started = true;
  return Status::ok();
}

Status LoopStage::process(FrameSlot& slot) {
  Impl& m = *impl_;
  const std::int64_t t0 = steadyNowNs();
  ++m.frames_seen;
  LoopFrameInput in;
  in.frame = slot.frame.index;
  in.t_ns = slot.frame.t_ns;
  in.world_epoch = slot.world_epoch;
  if (slot.world_epoch != m.lastWorldEpoch())
    m.world_starts.emplace_back(slot.frame.index, slot.world_epoch);
  in.T_world_cam = slot.result.T_world_cam;
  in.motion_valid = slot.result.odometry.tracked;
  in.T_cur_prev = slot.result.odometry.T_cur_prev;
  in.motion_cov = slot.result.odometry.covariance;
  in.pose_cov = slot.result.pose_cov;
  in.left = slot.frame.left.cview();
  in.dense = slot.stereo.has_disparity ? &slot.stereo.disparity : nullptr;
  auto item = std::make_unique<KeyframeItem>();
  bool made = false;
  if (Status s = m.front->process(in, made, item->kf, item->odo_cov, item->odo_T); !s)
    return Status(s.code(), "loop closing, frame " + std::to_string(slot.frame.index) + ": " +
                                s.message());
  if (m.front->lastKeyframe() >= 0) {
    const Eigen::Isometry3d& T = m.front->chainFromLastKeyframe();
    m.links.push_back({slot.frame.t_ns, m.front->lastKeyframe(), slot.world_epoch,
                       Eigen::Quaternionf(Eigen::Quaterniond(T.linear()).cast<float>()),
                       T.translation().cast<float>()});
  }
  {
    std::lock_guard<std::mutex> lock(m.fb_mutex);
    m.last_front = slot.frame.index;
    if (made) m.pending.push_back(slot.frame.index);
    m.updateResolved();
    m.fb_cv.notify_all();
  }
  if (made) {
    times_.add("keyframe", static_cast<double>(steadyNowNs() - t0) * 1e-6);
    StageWait waiting;  // on the back end's thread when its ring is full
    m.ring.wait_enqueue(std::move(item));
  }
  return Status::ok();
}

void LoopStage::setWaitForBackEnd(bool wait) {
  std::lock_guard<std::mutex> lock(impl_->fb_mutex);
  impl_->wait_for_back_end = wait;
}

void LoopStage::stopFeedback() {
  std::lock_guard<std::mutex> lock(impl_->fb_mutex);
  impl_->fb_stop = true;
  impl_->fb_cv.notify_all();
}

bool LoopStage::correctionBefore(std::int64_t frame, int world_epoch,
                                 Eigen::Isometry3d& C_new_old, Matrix6d& cov_world) {
  Impl& m = *impl_;
  if (!m.cfg.loop_feedback || !m.started) return false;
  const std::int64_t delay = m.cfg.loop_feedback_delay_frames;
  Impl::Solution due{-1, 0, Eigen::Isometry3d::Identity(), Matrix6d::Zero()};
  {
    std::unique_lock<std::mutex> lock(m.fb_mutex);
    if (m.wait_for_back_end && m.resolved < frame - delay && !m.fb_stop) {
      const std::int64_t w0 = steadyNowNs();
      StageWait waiting;  // on the back end
      // A bound against a stage that stopped without saying so: the run goes on, counted.
      if (!m.fb_cv.wait_for(lock, std::chrono::seconds(30),
                            [&] { return m.fb_stop || m.resolved >= frame - delay; }))
        ++m.feedback_wait_timeouts;
      m.feedback_wait_max_ms =
          std::max(m.feedback_wait_max_ms, static_cast<double>(steadyNowNs() - w0) * 1e-6);
    }
    while (!m.solutions.empty() && m.solutions.front().kf_frame + delay <= frame) {
      // The newest due solution supersedes older ones; one of an older world is dropped.
      if (m.solutions.front().world_epoch == world_epoch)
        due = m.solutions.front();
      else
        ++m.feedback_dropped_other_world;
      m.solutions.pop_front();
    }
  }
  if (due.kf_frame < 0) return false;
  C_new_old = due.C * Impl::appliedBetween(m.applied, due.kf_frame, frame).inverse();
  cov_world = due.cov;
  return true;
}

void LoopStage::correctionApplied(std::int64_t frame, const Eigen::Isometry3d& moved) {
  std::lock_guard<std::mutex> lock(impl_->fb_mutex);  // the mapper copies it (frameCorrections)
  impl_->applied.push_back({frame, moved});
}

bool LoopStage::Impl::frameCorrection(const Snapshot& snap, const std::vector<Applied>& moves,
                                      std::int64_t frame, Eigen::Isometry3d& M) const {
  if (snap.frame.empty()) return false;
  // The keyframe at or before `frame` (the first one for a frame before it).
  const auto it = std::upper_bound(snap.frame.begin(), snap.frame.end(), frame);
  const std::size_t k0 =
      it == snap.frame.begin() ? 0 : static_cast<std::size_t>(it - snap.frame.begin()) - 1;
  // After a reset, before the new world's first keyframe: that keyframe (none yet: no
  // correction).
  const int k = snap.keyframeForWorld(k0, worldOf(frame));
  if (k < 0) return false;
  const std::size_t ks = static_cast<std::size_t>(k);
  M = snap.C[ks] * appliedBetween(moves, snap.frame[ks], frame).inverse();
  return true;
}

bool LoopStage::Impl::frameCorrection(std::int64_t frame, Eigen::Isometry3d& M) const {
  return snapshot && frameCorrection(*snapshot, applied, frame, M);
}

Status LoopStage::Impl::writeLandmarks(const std::vector<MapLandmark>& map) const {
  std::vector<run::PlyLandmark> ply;
  ply.reserve(map.size());
  for (const MapLandmark& l : map) {
    // The correction of the frame the landmark was last estimated in (the last frame for one
    // still in the state).
    Eigen::Isometry3d M = Eigen::Isometry3d::Identity();
    (void)frameCorrection(l.active ? std::numeric_limits<std::int64_t>::max() : l.last_seen_frame,
                          M);
    const Eigen::Matrix3d C = M.linear() * l.cov * M.linear().transpose();
    ply.push_back({l.id, M * l.p_world, C.diagonal().cwiseMax(0.0).cwiseSqrt(), l.active,
                   l.observations});
  }
  return run::writeLandmarksPly(out_dir + "/" + run::files::kLandmarksOptimized, ply);
}

Status LoopStage::finish(const std::vector<MapLandmark>& map) {
  Impl& m = *impl_;
  if (!m.started) return Status::ok();
  if (!m.closed) {
    m.ring.wait_enqueue(nullptr);
    m.closed = true;
  }
  if (m.thread.joinable()) m.thread.join();
  if (!m.error) return m.error;
  // The published trajectory, every pose moved by the correction of its time.
  auto traj = drivers::readTrajectory(m.out_dir + "/" + run::files::kTrajectoryTum);
  if (!traj) return Status(traj.status().code(), "loop closing: " + traj.status().message());
  run::TrajectoryWriter w;
  if (Status s = w.open(m.out_dir + "/" + run::files::kTrajectoryOptimizedKitti,
                        m.out_dir + "/" + run::files::kTrajectoryOptimizedTum);
      !s)
    return s;
  // A frame the front end saw: its corrected keyframe times the online relative pose from it
  // when the filter's edge from that keyframe was used, else times the motion chain (the filter
  // jumped there, e.g. when anchors came back; after the last keyframe); a frame it skipped:
  // the online pose moved by the interpolated keyframe correction.
  const std::vector<Eigen::Isometry3d>& kf = m.closer->correctedKeyframes();
  std::size_t j = 0;
  for (std::size_t i = 0; i < traj->poses.size(); ++i) {
    const std::int64_t t = traj->t_ns[i];
    while (j < m.links.size() && m.links[j].t_ns < t) ++j;
    Eigen::Isometry3d T;
    if (!m.closer->solved()) {
      T = traj->poses[i];  // no loop closed: the online trajectory
    } else if (j < m.links.size() && m.links[j].t_ns == t &&
               static_cast<std::size_t>(m.links[j].kf) < kf.size() &&
               m.snapshot->world[static_cast<std::size_t>(m.links[j].kf)] !=
                   m.links[j].world_epoch) {
      // After a reset, before the new world's first keyframe: that keyframe's correction (the
      // end state's snapshot, taken when the closer had solved).
      const int k = m.snapshot->keyframeForWorld(static_cast<std::size_t>(m.links[j].kf),
                                                 m.links[j].world_epoch);
      T = k < 0 ? traj->poses[i] : m.snapshot->C[static_cast<std::size_t>(k)] * traj->poses[i];
    } else if (j < m.links.size() && m.links[j].t_ns == t &&
        static_cast<std::size_t>(m.links[j].kf) < kf.size()) {
      const std::size_t k = static_cast<std::size_t>(m.links[j].kf);
      if (k < m.closer->edges() && !m.closer->chainEdge(k)) {  // the filter agreed: its poses
        T = kf[k] * m.closer->onlineKeyframe(k).inverse() * traj->poses[i];
      } else {  // the filter jumped (or after the last keyframe): the motion chain
        Eigen::Isometry3d chain = Eigen::Isometry3d::Identity();
        chain.linear() = m.links[j].q.cast<double>().normalized().toRotationMatrix();
        chain.translation() = m.links[j].t.cast<double>();
        T = kf[k] * chain;
      }
    } else {
      T = m.closer->correctionAt(t) * traj->poses[i];
    }
    if (Status s = w.append(t, T); !s) return s;
  }
  if (Status s = w.close(); !s) return s;
  return map.empty() ? Status::ok() : m.writeLandmarks(map);
}

bool LoopStage::frameCorrection(std::int64_t frame, Eigen::Isometry3d& M) const {
  return impl_->frameCorrection(frame, M);
}

int LoopStage::solutionsMade() const { return impl_->solutions_made.load(); }

bool LoopStage::liveFrameCorrections(
    std::function<bool(std::int64_t, Eigen::Isometry3d&)>& out) const {
  Impl& m = *impl_;
  std::shared_ptr<const Impl::Snapshot> snap = m.latestSnapshot();
  if (!snap) return false;
  auto moves = std::make_shared<std::vector<Impl::Applied>>();
  {
    std::lock_guard<std::mutex> lock(m.fb_mutex);
    *moves = m.applied;
  }
  out = [&m, snap, moves](std::int64_t frame, Eigen::Isometry3d& M) {
    return m.frameCorrection(*snap, *moves, frame, M);
  };
  return true;
}

std::string LoopStage::json() const {
  const Impl& m = *impl_;
  cli::JsonObject o;
  if (!m.closer) return o.str();
  const LoopCloserStats& st = m.closer->stats();
  o.add("vocabulary_words", m.vocabulary_words);
  o.add("vocabulary_load_ms", m.vocabulary_load_ms, 1);
  o.add("frames_seen", m.frames_seen);
  o.add("keyframes", st.keyframes);
  o.add("place_candidates", st.candidates);
  o.add("verified", st.verified);
  o.add("rejected_verification", st.rejected_verification);
  o.add("rejected_consistency", st.rejected_consistency);
  o.add("loops_accepted", st.accepted);
  o.add("optimisations", st.optimisations);
  o.add("chain_edges", st.chain_edges);
  if (m.cfg.loop.wrong_loop_fraction > 0) {
    o.add("injected_wrong", st.injected_wrong);
    o.add("injected_wrong_accepted", st.injected_wrong_accepted);
  }
  o.add("last_max_correction_m", st.last_max_correction_m, 4);
  o.add("corrections_published", m.corrections_published);
  o.add("feedback_moves", static_cast<std::int64_t>(m.applied.size()));
  double moved_m = 0;  // |t| of the move: how far it shifts the world origin
  for (const Impl::Applied& a : m.applied) moved_m = std::max(moved_m, a.delta.translation().norm());
  o.add("feedback_max_translation_m", moved_m, 4);
  o.add("feedback_wait_max_ms", m.feedback_wait_max_ms, 1);
  o.add("feedback_wait_timeouts", m.feedback_wait_timeouts);
  o.add("world_resets", st.world_resets);
  o.add("feedback_dropped_other_world", m.feedback_dropped_other_world);
  double worst = 0;
  for (double v : m.solve_ms) worst = std::max(worst, v);
  o.add("back_end_max_ms", worst, 1);
  o.add("memory_bytes", static_cast<std::int64_t>(m.closer->memoryBytes()));
  std::string loops = "[";
  for (const AcceptedLoop& a : m.closer->acceptedLoops()) {
    char buf[256];
    std::snprintf(buf, sizeof buf,
                  "%s{\"query\": %d, \"candidate\": %d, \"query_frame\": %lld, "
                  "\"candidate_frame\": %lld, \"inliers\": %d}",
                  loops.size() > 1 ? ", " : "", a.query, a.candidate,
                  static_cast<long long>(a.query_frame), static_cast<long long>(a.candidate_frame),
                  a.inliers);
    loops += buf;
  }
  o.addRaw("accepted", loops + "]");
  return o.str();
}

#else  // no Ceres: loop closing is not built

bool loopClosingAvailable() { return false; }
struct LoopStage::Impl {};
LoopStage::LoopStage(const config::RunConfig&, drivers::StereoSource&, std::string,
                     drivers::LcmLink*) {}
LoopStage::~LoopStage() = default;
Status LoopStage::init() {
  return Status::failedPrecondition(
      "loop.enabled: this build has no loop closing (Ceres was not found when it was built)");
}
Status LoopStage::process(FrameSlot&) { return Status::ok(); }
bool LoopStage::correctionBefore(std::int64_t, int, Eigen::Isometry3d&,
                                 Eigen::Matrix<double, 6, 6>&) {
  return false;
}
void LoopStage::correctionApplied(std::int64_t, const Eigen::Isometry3d&) {}
void LoopStage::setWaitForBackEnd(bool) {}
void LoopStage::stopFeedback() {}
Status LoopStage::finish(const std::vector<MapLandmark>&) { return Status::ok(); }
bool LoopStage::frameCorrection(std::int64_t, Eigen::Isometry3d&) const { return false; }
int LoopStage::solutionsMade() const { return 0; }
bool LoopStage::liveFrameCorrections(std::function<bool(std::int64_t, Eigen::Isometry3d&)>&) const {
  return false;
}
std::string LoopStage::json() const { return "{}"; }

#endif

}  // namespace svslam::rt
