// Accuracy side by side: svslam (census 9x7, defaults) beside cv::StereoBM (9x9, texture 10,
// uniqueness 10, LR check 1) and cv::StereoSGBM (3-way, 5x5, P1 = 8*25, P2 = 32*25,
// uniqueness 10, LR check 1) on the Middlebury and KITTI cases of ../shared/data, scored by
// the same metrics (non-occluded pixels; aloe's mask derived from its ground truth).
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <string>

#include "drivers/files/opencv_view.hpp"
#include "eval/disparity_metrics.hpp"
#include "pipeline/tools/stereo_case.hpp"

namespace {

svslam::ImageF32 fromOpenCv(const cv::Mat& d16, int min_disp) {
  // OpenCV: int16 disparity * 16, invalid = (min_disp - 1) * 16.
  svslam::ImageF32 out(d16.cols, d16.rows);
  for (int y = 0; y < d16.rows; ++y)
    for (int x = 0; x < d16.cols; ++x) {
      const short v = d16.at<short>(y, x);
      out(x, y) = v < min_disp * 16 ? std::numeric_limits<float>::infinity() : v / 16.0f;
    }
  return out;
}

void print(const char* method, const std::string& name,
           const svslam::Result<svslam::DisparityMetrics>& m) {
  if (!m) {
    std::printf("%-10s %-36s error: %s\n", method, name.c_str(), m.status().message().c_str());
    return;
  }
  std::printf(
      "%-10s %-36s bad1(valid) %6.2f %%  bad3(valid) %6.2f %%  density %6.2f %%  bad1(all) %6.2f "
      "%%\n",
      method, name.c_str(), m->bad1_valid_pct, m->bad3_valid_pct, m->density_pct, m->bad1_all_pct);
}

}  // namespace

int main() {
  const std::string data = SVSLAM_DATA_DIR;
  const char* cases[] = {"middlebury_v2/tsukuba", "middlebury_v2/venus", "middlebury_v2/teddy",
                         "middlebury_v2/cones",   "middlebury2006_aloe", "kitti_stereo2012_000070"};
  if (!std::filesystem::exists(data)) {
    std::printf("compare_accuracy: %s absent, nothing to compare\n", data.c_str());
    return 0;
  }
  cv::setNumThreads(1);
  svslam::SerialExecutor ex;
  for (const char* c : cases) {
    auto info = svslam::drivers::findStereoGtCase(data + "/" + c, "nonocc", "");
    if (!info) continue;
    auto loaded = svslam::cli::loadCase(*info, true, true);
    if (!loaded) continue;
    const int nd = (info->max_disp + 15) / 16 * 16;  // OpenCV wants a multiple of 16
    svslam::DenseStereoParams p;
    p.max_disp = info->max_disp;
    if (std::string(c).rfind("kitti", 0) == 0) p.uniqueness_pct = 0;
    svslam::DisparityResult r;
    if (svslam::cli::computeDisparity(*loaded, p, ex, r, nullptr))
      print("svslam", info->name,
            svslam::evaluateDisparity(r.disparity_px.cview(), loaded->gt.cview(),
                                      loaded->mask.cview()));
    cv::Mat d;
    auto bm = cv::StereoBM::create(nd, 9);
    bm->setTextureThreshold(10);
    bm->setUniquenessRatio(10);
    bm->setDisp12MaxDiff(1);
    bm->compute(svslam::drivers::asMat(loaded->left), svslam::drivers::asMat(loaded->right), d);
    print("StereoBM", info->name,
          svslam::evaluateDisparity(fromOpenCv(d, 0).cview(), loaded->gt.cview(),
                                    loaded->mask.cview()));
    auto sgbm = cv::StereoSGBM::create(0, nd, 5, 8 * 25, 32 * 25, 1, 63, 10, 100, 2,
                                       cv::StereoSGBM::MODE_SGBM_3WAY);
    sgbm->compute(svslam::drivers::asMat(loaded->left), svslam::drivers::asMat(loaded->right), d);
    print("SGBM-3way", info->name,
          svslam::evaluateDisparity(fromOpenCv(d, 0).cview(), loaded->gt.cview(),
                                    loaded->mask.cview()));
  }
  return 0;
}
