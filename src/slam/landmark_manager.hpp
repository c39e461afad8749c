#pragma once
// Bookkeeping of the SLAM filter's landmarks and of the per-point tracks (seed 001 sec 4.2).
//
// Every stereo point of a frame carries a track: how many consecutive frames it has been
// matched (track_len) and whether it is a candidate landmark. Matches pass the track on from the
// previous frame's point to the current one.
// Landmarks in the map keep an appearance patch (from their last observation; used to find them
// again in the next frame and after a loop), where and when they were last observed, and, once
// retired from the filter state, their final position and covariance (kept in the map file, out
// of the state).
#include <Eigen/Core>
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
  float last_u_px = 0, last_v_px = 0;  // left image position at the last observation
  int observations = 0;
};

// Appearance and history of landmarks, by id.
class LandmarkManager {
 public:
  explicit LandmarkManager(int patch_half_px) : h_(patch_half_px) {}
  int patchHalf() const { return h_; }
  int patchSide() const { return 2 * h_ + 1; }
  // Registers a new landmark observed at (u, v) with the patch of `img` centred on the nearest
  // pixel (inside the image).
  void add(int id, int frame, ImageView<const std::uint8_t> img, float u, float v);
  // A new observation at (u, v): position, frame and patch updated.
  void observed(int id, int frame, ImageView<const std::uint8_t> img, float u, float v);
  // The stored patch as an image view (patchSide() square).
  ImageView<const std::uint8_t> patch(int id) const;
  MapLandmark& info(int id) { return info_.at(id); }
  const MapLandmark& info(int id) const { return info_.at(id); }
  bool contains(int id) const { return info_.count(id) != 0; }
  const std::map<int, MapLandmark>& all() const { return info_; }

 private:
  int h_;
  std::map<int, MapLandmark> info_;
  std::map<int, std::vector<std::uint8_t>> patches_;
};

}  // namespace svslam
