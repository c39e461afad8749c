#include "pipeline/tools/disparity_output.hpp"

#include "drivers/files/image_io.hpp"

namespace svslam::cli {
namespace {

bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace

Status checkOutputPath(const std::string& path, const std::string& what) {
  const bool pfm = endsWith(path, ".pfm");
  const bool png = endsWith(path, ".png");
  if (what == "out" && !pfm && !png)
    return Status::invalidArgument("--out " + path + ": use a .pfm or .png file name");
  if (what == "sigma" && !pfm)
    return Status::invalidArgument("--sigma " + path + ": use a .pfm file name");
  if (what == "color" && !png)
    return Status::invalidArgument("--color " + path + ": use a .png file name");
  return Status::ok();
}

Status writeDisparityOutputs(const DisparityResult& r, const std::string& disparity_path,
                             const std::string& sigma_path, const std::string& color_path,
                             int max_disp) {
  if (!disparity_path.empty()) {
    Status s = endsWith(disparity_path, ".pfm")
                   ? drivers::writePfm(disparity_path, r.disparity_px.cview())
                   : drivers::writeDisparityPng16(disparity_path, r.disparity_px.cview());
    if (!s) return s;
  }
  if (!sigma_path.empty()) {
    if (Status s = drivers::writePfm(sigma_path, r.sigma_d_px.cview()); !s) return s;
  }
  if (!color_path.empty()) {
    if (Status s =
            drivers::writeColorPng(color_path, r.disparity_px.cview(), static_cast<float>(max_disp));
        !s)
      return s;
  }
  return Status::ok();
}

}  // namespace svslam::cli
