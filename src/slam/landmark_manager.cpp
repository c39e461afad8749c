#include "slam/landmark_manager.hpp"

#include <algorithm>
#include <cmath>

namespace svslam {

LandmarkManager::LandmarkManager(int patch_half_px, int reserve_landmarks, double voxel_m)
    : h_(patch_half_px), big_(2 * patch_half_px), retired_(voxel_m, reserve_landmarks) {
  const std::size_t n = static_cast<std::size_t>(std::max(reserve_landmarks, 0));
  slot_of_id_.reserve(static_cast<int>(n));
  free_slots_.reserve(n);
  info_.reserve(n);
  views_.reserve(n);
  patches_.reserve(n * patchBytes());
}

void LandmarkManager::add(int id, int frame, ImageView<const std::uint8_t> img, int x, int y,
                          const Eigen::Isometry3d& T_world_cam, const Eigen::Vector3d& p_cam) {
  int slot = slot_of_id_.find(id);
  if (slot < 0) {
    if (!free_slots_.empty()) {
      slot = free_slots_.back();
      free_slots_.pop_back();
    } else {
      slot = static_cast<int>(info_.size());
      info_.emplace_back();
      views_.emplace_back();
      patches_.resize(patches_.size() + patchBytes());
    }
    slot_of_id_.set(id, slot);
    ++slots_used_;
  }
  const std::size_t sl = static_cast<std::size_t>(slot);
  MapLandmark m;
  m.id = id;
  m.active = true;
  m.created_frame = frame;
  m.last_seen_frame = frame;
  info_[sl] = m;
  views_[sl] = {T_world_cam.linear(), p_cam};
  copyPatch(img, x, y, big_, patches_.data() + sl * patchBytes());
}

void LandmarkManager::retire(int id) {
  MapLandmark& m = info(id);
  m.active = false;
  if (m.anchored) return;
  retired_.insert(m);
  free_slots_.push_back(static_cast<int>(slotOf(id)));
  slot_of_id_.erase(id);
  --slots_used_;
}

std::vector<MapLandmark> LandmarkManager::landmarks() const {
  std::vector<MapLandmark> out;
  out.reserve(static_cast<std::size_t>(size()));
  slot_of_id_.forEach(
      [&](int /*id*/, int slot) { out.push_back(info_[static_cast<std::size_t>(slot)]); });
  out.insert(out.end(), retired_.landmarks().begin(), retired_.landmarks().end());
  std::sort(out.begin(), out.end(),
            [](const MapLandmark& a, const MapLandmark& b) { return a.id < b.id; });
  return out;
}

void LandmarkManager::copyPatch(ImageView<const std::uint8_t> img, int x, int y, int half,
                                std::uint8_t* out) {
  const int s = 2 * half + 1;
  for (int dy = -half; dy <= half; ++dy)
    for (int dx = -half; dx <= half; ++dx)
      out[(dy + half) * s + dx + half] =
          img(std::clamp(x + dx, 0, img.width - 1), std::clamp(y + dy, 0, img.height - 1));
}

bool LandmarkManager::templateFor(int id, const Eigen::Matrix3d& R_world_cam,
                                  const Eigen::Vector3d& p_cam_now, double f_px,
                                  std::uint8_t* out) const {
  const View& v = views_[slotOf(id)];
  const double z = p_cam_now.z();
  if (!(z > 0.0) || !(v.p_cam.z() > 0.0)) return false;
  Eigen::Matrix<double, 2, 3> J;
  J << f_px / z, 0, -f_px * p_cam_now.x() / (z * z), 0, f_px / z, -f_px * p_cam_now.y() / (z * z);
  const Eigen::Matrix3d R_now_init = R_world_cam.transpose() * v.R_world_cam;
  const Eigen::Matrix2d A = J * R_now_init.leftCols<2>() * (v.p_cam.z() / f_px);
  const double det = A.determinant();
  if (!(std::abs(det) > 1e-6)) return false;
  const Eigen::Matrix2d Ai = A.inverse();  // delta_init = Ai delta_now
  const std::uint8_t* p = patches_.data() + slotOf(id) * patchBytes();
  const int s = 2 * big_ + 1;
  for (int dy = -h_; dy <= h_; ++dy)
    for (int dx = -h_; dx <= h_; ++dx) {
      const Eigen::Vector2d q = Ai * Eigen::Vector2d(dx, dy) + Eigen::Vector2d(big_, big_);
      const int x0 = static_cast<int>(std::floor(q.x())), y0 = static_cast<int>(std::floor(q.y()));
      if (x0 < 0 || y0 < 0 || x0 + 1 >= s || y0 + 1 >= s) return false;
      const double ax = q.x() - x0, ay = q.y() - y0;
      auto at = [&](int xx, int yy) {
        return static_cast<double>(p[static_cast<std::size_t>(yy * s + xx)]);
      };
      const double val = (1 - ay) * ((1 - ax) * at(x0, y0) + ax * at(x0 + 1, y0)) +
                         ay * ((1 - ax) * at(x0, y0 + 1) + ax * at(x0 + 1, y0 + 1));
      out[(dy + h_) * (2 * h_ + 1) + dx + h_] = static_cast<std::uint8_t>(std::lround(val));
    }
  return true;
}

void LandmarkManager::observed(int id, int frame) {
  MapLandmark& m = info(id);
  m.last_seen_frame = frame;
  ++m.observations;
}

}  // namespace svslam
