#pragma once
// Bookkeeping of the SLAM filter's landmarks and of the per-point tracks (seed 001 sec 4.2).
//
// Every stereo point of a frame carries a track: how many consecutive frames it has been
// matched (track_len) and whether it is a candidate landmark. Matches pass the track on from the
// previous frame's point to the current one.
// Landmarks in the map keep an appearance patch (taken at initialisation, centred on the pixel
// the landmark was initialised from, and never updated, so that every observation refers to
// the same world point: an updated template would drift by its re-centring) with the camera
// pose and the camera-frame point of that moment, so the patch can be warped to the predicted
// view (templateFor), when they were last observed, and, once
// retired from the filter state, their final position and covariance (kept in the map file, out
// of the state).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <map>
#include <vector>

#include "core/image.hpp"

namespace svslam {

struct PointTrack {
  int track_len = 1;  // consecutive frames in which this point was matched
  bool candidate = false;
};

struct MapLandmark {
  int id = -1;
  Eigen::Vector3d p_world = Eigen::Vector3d::Zero();  // metres
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();      // m^2
  bool active = false;  // in the filter state (else retired)
  int created_frame = 0;
  int last_seen_frame = 0;
  int observations = 0;
};

// Appearance and history of landmarks, by id.
class LandmarkManager {
 public:
  explicit LandmarkManager(int patch_half_px) : h_(patch_half_px), big_(2 * patch_half_px) {}
  int patchHalf() const { return h_; }
  int patchSide() const { return 2 * h_ + 1; }
  // Registers a new landmark initialised at integer pixel (x, y) of `img`, seen from
  // T_world_cam at p_cam (metres); the stored patch has half size 2 h (room for rotations).
  void add(int id, int frame, ImageView<const std::uint8_t> img, int x, int y,
           const Eigen::Isometry3d& T_world_cam, const Eigen::Vector3d& p_cam);
  // The (2h+1)^2 template of landmark `id` as it should look from a camera with rotation
  // R_world_cam where the landmark is at p_cam_now (metres): the stored patch warped by the
  // affine map of a surface element facing the initial camera,
  //     delta_now = J(p_now) R_now_init [I2; 0] (z_init / f) delta_init,
  // J the pinhole Jacobian. Bilinear sampling; false when the map is degenerate or the
  // template leaves the stored patch. `out` is a (2h+1)^2 buffer (row-major).
  bool templateFor(int id, const Eigen::Matrix3d& R_world_cam, const Eigen::Vector3d& p_cam_now,
                   double f_px, std::uint8_t* out) const;
  // A new observation in `frame`.
  void observed(int id, int frame);

  MapLandmark& info(int id) { return info_.at(id); }
  const MapLandmark& info(int id) const { return info_.at(id); }
  bool contains(int id) const { return info_.count(id) != 0; }
  const std::map<int, MapLandmark>& all() const { return info_; }

 private:
  struct View {
    Eigen::Matrix3d R_world_cam;
    Eigen::Vector3d p_cam;
  };
  int h_, big_;
  std::map<int, MapLandmark> info_;
  std::map<int, View> views_;
  std::map<int, std::vector<std::uint8_t>> patches_;
};

}  // namespace svslam
