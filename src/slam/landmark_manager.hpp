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
// Storage: a landmark in the state, or an anchored one (it may come back, SlamSystem step 5),
// holds a slot: record, view and patch (about 0.7 kB with the default patch). A landmark
// retired for good (retire()) frees its slot for the next new landmark and goes to the
// RetiredLandmarkMap (at most one per voxel of voxel_m, about 0.2 kB each), so memory is bounded
// by the state size, the anchors and the volume the map covers, not by the flight time (the
// id -> slot table is a hash map of the ids holding a slot: ids are EkfSlam's, handed out for
// ever, but only those in the state or anchored are in it). Slots, the id table and the retired
// map are preallocated for `reserve_landmarks`; beyond that they grow by doubling (one
// allocation per doubling, none per frame in between).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "core/image.hpp"
#include "slam/id_slot_map.hpp"
#include "slam/map_landmark.hpp"
#include "slam/retired_landmark_map.hpp"

namespace svslam {

struct PointTrack {
  int track_len = 1;  // consecutive frames in which this point was matched
  bool candidate = false;
  int anchor = -1;  // a candidate of the first frame: its index in SlamSystem's anchor_points_
};


// Appearance and history of landmarks, by id.
class LandmarkManager {
 public:
  // `reserve_landmarks`: ids (0 .. reserve_landmarks - 1) whose storage is preallocated, >= 0.
  // voxel_m: side of the retired map's voxels, metres, > 0.
  LandmarkManager(int patch_half_px, int reserve_landmarks, double voxel_m);
  int patchHalf() const { return h_; }
  int patchSide() const { return 2 * h_ + 1; }
  // Registers a new landmark initialised at integer pixel (x, y) of `img`, seen from
  // T_world_cam at p_cam (metres); the stored patch has half size 2 h (room for rotations).
  void add(int id, int frame, ImageView<const std::uint8_t> img, int x, int y,
           const Eigen::Isometry3d& T_world_cam, const Eigen::Vector3d& p_cam);
  // Copies the (2 half + 1)^2 patch of `img` centred on (x, y), row-major, into `out`; pixels
  // beyond the border repeat the nearest edge pixel.
  static void copyPatch(ImageView<const std::uint8_t> img, int x, int y, int half,
                        std::uint8_t* out);
  // The (2h+1)^2 template of landmark `id` as it should look from a camera with rotation
  // R_world_cam where the landmark is at p_cam_now (metres): the stored patch warped by the
  // affine map of a surface element facing the initial camera,
  //     delta_now = J(p_now) R_now_init [I2; 0] (z_init / f) delta_init,
  // J the pinhole Jacobian. Bilinear sampling; false when the map is degenerate or the
  // template leaves the stored patch. `out` is a (2h+1)^2 buffer (row-major).
  bool templateFor(int id, const Eigen::Matrix3d& R_world_cam, const Eigen::Vector3d& p_cam_now,
                   double f_px, std::uint8_t* out) const;
  // The world frame of landmark `id` (holding a slot) turned by R_new_old: its initial view's
  // R_world_cam <- R_new_old R_world_cam (SlamSystem::moveWorld).
  void rotateView(int id, const Eigen::Matrix3d& R_new_old) {
    View& v = views_[slotOf(id)];
    v.R_world_cam = R_new_old * v.R_world_cam;
  }
  // A new observation in `frame`.
  void observed(int id, int frame);

  // Landmark `id` holding a slot (precondition: contains(id)).
  MapLandmark& info(int id) { return info_[slotOf(id)]; }
  const MapLandmark& info(int id) const { return info_[slotOf(id)]; }
  // Whether `id` holds a slot: in the state, or anchored.
  bool contains(int id) const {
    return slot_of_id_.contains(id);
  }
  // Landmark `id` (holding a slot, its record up to date) has left the filter state: an anchored
  // one keeps its slot (inactive); any other goes to the retired map and frees its slot.
  void retire(int id);
  // Landmarks in the map: holding a slot, or kept in the retired map.
  int size() const { return slots_used_ + retired_.size(); }
  // Every landmark of the map (slots and retired map), sorted by id.
  std::vector<MapLandmark> landmarks() const;
  const RetiredLandmarkMap& retiredMap() const { return retired_; }

 private:
  struct View {
    Eigen::Matrix3d R_world_cam;
    Eigen::Vector3d p_cam;
  };
  std::size_t slotOf(int id) const {
    return static_cast<std::size_t>(slot_of_id_.find(id));
  }
  std::size_t patchBytes() const {
    return static_cast<std::size_t>((2 * big_ + 1) * (2 * big_ + 1));
  }
  int h_, big_;
  IdSlotMap slot_of_id_;               // slot of each id holding one (in the state or anchored)
  std::vector<int> free_slots_;        // slots to reuse, the last freed first
  int slots_used_ = 0;
  std::vector<MapLandmark> info_;      // by slot
  std::vector<View> views_;            // by slot
  std::vector<std::uint8_t> patches_;  // by slot, patchBytes() each: (4h+1)^2 grey levels
  RetiredLandmarkMap retired_;
};

}  // namespace svslam
