#include "pipeline/tools/stereo_case.hpp"

#include <chrono>
#include <sstream>

#include "drivers/files/image_io.hpp"
#include "eval/occlusion_mask.hpp"

namespace svslam::cli {

std::vector<std::string> splitList(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string part;
  while (std::getline(ss, part, ','))
    if (!part.empty()) out.push_back(part);
  return out;
}

Result<LoadedCase> loadCase(const drivers::StereoGtCase& info, bool with_images, bool derive_nonocc) {
  LoadedCase c;
  c.info = info;
  if (with_images) {
    auto l = drivers::loadGrey(info.left);
    if (!l) return l.status();
    auto r = drivers::loadGrey(info.right);
    if (!r) return r.status();
    c.left = std::move(l).value();
    c.right = std::move(r).value();
    if (c.left.width() != c.right.width() || c.left.height() != c.right.height())
      return Status::invalidArgument("left and right images of " + info.name + " differ in size");
  }
  auto gt = drivers::loadDisparity(info.gt, info.gt_scale);
  if (!gt) return gt.status();
  c.gt = std::move(gt).value();
  if (!info.mask.empty()) {
    auto m = drivers::loadMask(info.mask);
    if (!m) return m.status();
    c.mask = std::move(m).value();
  } else if (derive_nonocc) {
    c.mask = nonOccludedMask(c.gt.cview());
  }
  return c;
}

Status computeDisparity(const LoadedCase& c, DenseStereoParams params, Executor& executor,
                        DisparityResult& out, double* compute_ms) {
  if (params.max_disp <= 0) params.max_disp = c.info.max_disp;
  DenseStereo stereo(params, c.left.width(), c.left.height());
  if (!stereo.initStatus()) return stereo.initStatus();
  const auto t0 = std::chrono::steady_clock::now();
  Status s = stereo.process(c.left.cview(), c.right.cview(), out, executor);
  if (compute_ms != nullptr)
    *compute_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return s;
}

}  // namespace svslam::cli
