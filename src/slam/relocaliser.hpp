#pragma once
// Relocalisation against the map after a real loss of tracking (the images gone for a while:
// lens covered, camera restarted, a blur): the pose comes back from what was seen before, not
// from a reset to the identity or a prediction that has drifted away.
//
// While tracking is good, keyframes (loop/keyframe.hpp: ORB points of the left image with a 3D
// point and covariance from the dense disparity, the filter's pose and pose covariance) are kept
// in a ring of max_keyframes, made by the keyframe rule (travel or rotation since the last one).
// With pending_keyframes > 0 a keyframe is not built when it is kept: its left image and dense
// disparity (and sigma) are copied into a ring of that many pending keyframes, and it is built
// (its ORB extraction) only when a lost frame is verified against it, then moves to the ring of
// built keyframes; a pending keyframe that leaves its ring unbuilt is dropped. Tracking then pays
// a copy per keyframe, not an extraction; a loss pays the extractions of the pending keyframes
// it needs, at most max_builds_per_frame of them per lost frame. The rule's median depth of a pending keyframe is that of its dense disparity
// (every 4th pixel of every 4th row), not of its ORB points.
// On a lost frame (SlamSystem: the frame-to-frame motion failed and fewer than min_landmarks
// landmarks were observed) the current frame becomes a query keyframe; the kept keyframes are
// taken nearest the predicted camera position first (its error after a loss is what is
// unknown, the ring is small), at most max_candidates of them, each verified as a loop is
// (loop/loop_verifier.hpp: mutual Hamming matching with a ratio test, seeded RANSAC 3D-3D
// motion, k-sigma rejection, Haralick covariance, min_inliers); the first accepted gives, with
// T_qk = T_query_candidate (a point of the keyframe in the query camera: p_q = T_qk p_k),
//     T_world_cur = T_world_kf T_qk^-1,
// and its covariance ([dtheta, dt], world frame) to first order from the keyframe's pose
// covariance and the constraint's (loop/relative_pose.hpp's inversion and product Jacobians).
// The ring bounds memory (about 25 kB a built keyframe: 400 points of 48 bytes, no BoW vector;
// 9 bytes a pixel a pending one: 1.8 MB at 512x384, 7.1 MB at 1024x768) and the work of a lost
// frame (max_candidates verifications, each pending candidate built first). A keyframe's ORB
// extraction costs 44 ms at 512x384 and 167 ms at 1024x768 on the 2-core VM, on the caller's
// thread.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "core/camera.hpp"
#include "core/image.hpp"
#include "core/status.hpp"
#include "loop/keyframe.hpp"
#include "loop/loop_verifier.hpp"
#include "stereo/dense_stereo.hpp"

namespace svslam {

struct RelocaliserParams {
  // Keep keyframes and relocalise lost frames (docs/slam.md "Lost frames").
  bool enabled = true;
  KeyframeParams keyframe;  // rule and content of the keyframes (loop closing's defaults)
  LoopVerifierParams verify;  // acceptance of a relocalisation (min_inliers, ...)
  int max_keyframes = 200;    // ring size, 1..100000
  // Newest keyframes kept pending (image and disparity, built when a loss needs them), 0..100;
  // 0 builds every keyframe when it is kept (an ORB extraction per keyframe while tracking).
  int pending_keyframes = 4;
  // Pending keyframes built per lost frame at most (the nearest first; the next lost frame
  // builds the next ones), 1..100: bounds a lost frame's work to this many extractions and its
  // own (3 x 44 ms at 512x384, 3 x 167 ms at 1024x768).
  int max_builds_per_frame = 2;
  int max_candidates = 8;     // keyframes verified per lost frame, 1..1000
  int min_landmarks = 6;      // a frame without motion and fewer landmark observations is lost
  // Lost frames with points whose relocalisation failed before the loss is given up: the
  // filter goes on from its prediction (new landmarks and keyframes again), 1..100000. Frames
  // without points (black, blank) do not count: they cost nothing to wait through.
  int max_lost_frames = 20;
  Status validate() const;
};

struct RelocalisationResult {
  bool found = false;
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Zero();  // [dtheta, dt]
  std::int64_t keyframe_frame = -1;  // the keyframe it was found against
  int inliers = 0;
  int candidates_tried = 0;
  const char* reason = "";  // why not found
};

class Relocaliser {
 public:
  Relocaliser(const RelocaliserParams& params, const StereoCalibration& calib);
  const Status& initStatus() const { return init_status_; }
  // A well-tracked frame (rectified left image, its dense disparity, the filter's pose and pose
  // covariance): kept as a keyframe when the rule says so (`kept`). A frame with too few points
  // is not kept (not an error).
  Status offer(ImageView<const std::uint8_t> left, const DisparityResult& dense,
               const Eigen::Isometry3d& T_world_cam, const Eigen::Matrix<double, 6, 6>& pose_cov,
               std::int64_t frame, bool& kept);
  // A lost frame: its pose against the kept keyframes, nearest T_world_pred first (above).
  Status relocalise(ImageView<const std::uint8_t> left, const DisparityResult& dense,
                    const Eigen::Isometry3d& T_world_pred, std::int64_t frame,
                    RelocalisationResult& out);
  // Built keyframes, and pending ones (not built yet).
  int keyframes() const { return static_cast<int>(ring_.size()); }
  int pendingKeyframes() const;

 private:
  struct Pending {
    bool used = false;  // holds a keyframe not built yet
    ImageU8 left;
    DisparityResult dense;  // disparity_px and sigma_d_px (what the builder reads)
    Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();
    Eigen::Matrix<double, 6, 6> pose_cov = Eigen::Matrix<double, 6, 6>::Zero();
    std::int64_t frame = -1;
  };
  // Median depth (m) of the valid disparities of a grid of pixels; false when fewer than 16.
  bool medianDepth(const DisparityResult& dense, double& depth_m);
  void addToRing(Keyframe& kf);  // swapped in (kf receives the replaced one)
  Status keepPending(ImageView<const std::uint8_t> left, const DisparityResult& dense,
                     const Eigen::Isometry3d& T_world_cam,
                     const Eigen::Matrix<double, 6, 6>& pose_cov, std::int64_t frame,
                     bool& kept);
  RelocaliserParams params_;
  Status init_status_;
  KeyframeSelector selector_;
  KeyframeBuilder builder_;
  LoopVerifier verifier_;
  StereoCalibration calib_;
  std::vector<Keyframe> ring_;
  std::size_t next_ = 0;  // ring slot replaced next once full
  std::vector<Pending> pending_;
  std::size_t pending_next_ = 0;  // pending slot replaced next
  Keyframe query_;
  std::vector<Keyframe> built_now_;  // pending keyframes built by one relocalise() call
  std::vector<float> disparities_;   // medianDepth's samples
  // Candidates: distance^2 to the predicted position, index, pending (else built).
  struct Candidate {
    double d2;
    std::size_t index;
    bool pending;
    bool operator<(const Candidate& o) const {
      return d2 != o.d2 ? d2 < o.d2 : (pending != o.pending ? !pending : index < o.index);
    }
  };
  std::vector<Candidate> order_;
};

}  // namespace svslam
