#include "slam/landmark_manager.hpp"

#include <algorithm>
#include <cmath>

namespace svslam {

void LandmarkManager::add(int id, int frame, ImageView<const std::uint8_t> img, float u, float v) {
  MapLandmark m;
  m.id = id;
  m.active = true;
  m.created_frame = frame;
  info_[id] = m;
  patches_[id].resize(static_cast<std::size_t>(patchSide() * patchSide()));
  observed(id, frame, img, u, v);
  info_[id].observations = 0;
}

void LandmarkManager::observed(int id, int frame, ImageView<const std::uint8_t> img, float u,
                               float v) {
  MapLandmark& m = info_.at(id);
  m.last_seen_frame = frame;
  m.last_u_px = u;
  m.last_v_px = v;
  ++m.observations;
  const int x = std::clamp(static_cast<int>(std::lround(u)), h_, img.width - h_ - 1);
  const int y = std::clamp(static_cast<int>(std::lround(v)), h_, img.height - h_ - 1);
  const int s = patchSide();
  std::vector<std::uint8_t>& p = patches_.at(id);
  for (int dy = 0; dy < s; ++dy)
    for (int dx = 0; dx < s; ++dx)
      p[static_cast<std::size_t>(dy * s + dx)] = img(x - h_ + dx, y - h_ + dy);
}

ImageView<const std::uint8_t> LandmarkManager::patch(int id) const {
  const auto& p = patches_.at(id);
  return ImageView<const std::uint8_t>(p.data(), patchSide(), patchSide(), patchSide());
}

}  // namespace svslam
