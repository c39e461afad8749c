// BinaryVocabulary and PlaceDatabase on real images: the KITTI odometry excerpt (51 frames,
// about 60 m, nearly straight). A vocabulary trained on the left images recognises each right
// image's place among the left images, and the score falls with the distance between frames.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "drivers/files/image_io.hpp"
#include "features/orb_extractor.hpp"
#include "loop/binary_vocabulary.hpp"
#include "loop/place_database.hpp"

namespace svslam {
namespace {

namespace fs = std::filesystem;

std::vector<std::vector<OrbDescriptor>> extractAll(const std::string& dir, int n) {
  std::vector<std::vector<OrbDescriptor>> out;
  std::vector<OrbKeypoint> kp;
  std::unique_ptr<OrbExtractor> orb;
  int orb_w = 0, orb_h = 0;
  for (int i = 0; i < n; ++i) {
    char name[32];
    std::snprintf(name, sizeof(name), "%06d.png", i);
    auto img = drivers::loadGrey(dir + "/" + name);
    if (!img) return {};
    if (!orb || orb_w != img->width() || orb_h != img->height()) {
      orb_w = img->width();
      orb_h = img->height();
      orb = std::make_unique<OrbExtractor>(OrbParams{}, orb_w, orb_h);
    }
    out.emplace_back();
    EXPECT_TRUE(orb->process(img->view(), kp, out.back()).isOk());
  }
  return out;
}

TEST(LoopRealImages, KittiRightImagesFindTheirLeftPlace) {
  const std::string dir = std::string(SVSLAM_DATA_DIR) + "/kitti_odometry_seq_a";
  if (!fs::exists(dir + "/image_l/000000.png"))
    GTEST_SKIP() << "no KITTI excerpt at " << dir << " (see ../shared/data/README.md)";
  constexpr int kFrames = 51;
  const auto left = extractAll(dir + "/image_l", kFrames);
  const auto right = extractAll(dir + "/image_r", kFrames);
  ASSERT_EQ(left.size(), static_cast<std::size_t>(kFrames));
  ASSERT_EQ(right.size(), static_cast<std::size_t>(kFrames));
  auto voc = BinaryVocabulary::train(left, VocabularyParams{});
  ASSERT_TRUE(voc.isOk()) << voc.status().message();

  std::vector<BowVector> l(kFrames), r(kFrames);
  for (int i = 0; i < kFrames; ++i) {
    voc->transform(left[static_cast<std::size_t>(i)], l[static_cast<std::size_t>(i)]);
    voc->transform(right[static_cast<std::size_t>(i)], r[static_cast<std::size_t>(i)]);
  }
  int within2 = 0;
  double near_sum = 0, far_sum = 0;
  int near_n = 0, far_n = 0;
  for (int i = 0; i < kFrames; ++i) {
    int best = -1;
    double best_s = -1;
    for (int j = 0; j < kFrames; ++j) {
      const double s =
          BinaryVocabulary::score(r[static_cast<std::size_t>(i)], l[static_cast<std::size_t>(j)]);
      if (s > best_s) best_s = s, best = j;
      if (std::abs(i - j) == 1) near_sum += s, ++near_n;
      if (std::abs(i - j) >= 30) far_sum += s, ++far_n;
    }
    within2 += std::abs(best - i) <= 2;
  }
  std::printf(
      "%d words; right image's best left within 2 frames: %d / %d; mean score at 1 "
      "frame %.3f, at >= 30 frames %.3f\n",
      voc->numWords(), within2, kFrames, near_sum / near_n, far_sum / far_n);
  EXPECT_GE(within2, kFrames * 8 / 10);
  EXPECT_GT(near_sum / near_n, 1.4 * far_sum / far_n);

  // The database answers a query of a right image that revisits the start of the drive.
  PlaceDatabaseParams dp;
  dp.temporal_consistency = 1;
  PlaceDatabase db(dp);
  for (int i = 0; i < kFrames; ++i) ASSERT_TRUE(db.add(i, l[static_cast<std::size_t>(i)]).isOk());
  // Query id kFrames + 1 with its "previous keyframe" kFrames - 1 missing -> add a copy of r[5]
  // as keyframe kFrames, so the prior is that of a same-place image.
  ASSERT_TRUE(db.add(kFrames, r[5]).isOk());
  std::vector<PlaceCandidate> out;
  ASSERT_TRUE(db.query(r[6], kFrames + 1, out).isOk());
  ASSERT_FALSE(out.empty());
  EXPECT_LE(std::abs(out[0].keyframe_id - 6), 2);
}

}  // namespace
}  // namespace svslam
