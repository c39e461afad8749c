#include "drivers/datasets/stereo_datasets.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include "drivers/files/image_io.hpp"

namespace svslam::drivers {
namespace {

namespace fs = std::filesystem;

bool isFile(const fs::path& p) {
  std::error_code ec;
  return fs::is_regular_file(p, ec);
}

bool isDir(const fs::path& p) {
  std::error_code ec;
  return fs::is_directory(p, ec);
}

// Regular files directly inside dir, sorted by name.
std::vector<std::string> listFiles(const fs::path& dir) {
  std::vector<std::string> names;
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    if (it->is_regular_file(ec)) names.push_back(it->path().filename().string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

std::string folderName(const fs::path& dir) {
  fs::path p = dir.lexically_normal();
  if (p.filename().empty()) p = p.parent_path();
  std::string name = p.filename().string();
  if (name.empty() || name == "." || name == "..") {
    std::error_code ec;
    const fs::path abs = fs::weakly_canonical(dir, ec);
    if (!ec && !abs.filename().empty()) name = abs.filename().string();
  }
  return name;
}

bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

Status missing(const fs::path& p) {
  return Status::notFound("stereo dataset file does not exist: " + p.string());
}

// Middlebury v2 info.txt: scale on the first non-empty line, max disparity on the second.
Result<StereoGtCase> middleburyV2(const fs::path& dir, const std::string& mask_kind) {
  const fs::path info = dir / "info.txt";
  std::ifstream in(info);
  if (!in) return Status::ioError("cannot open " + info.string());
  std::vector<std::string> lines;
  for (std::string line; lines.size() < 2 && std::getline(in, line);) {
    if (line.find_first_not_of(" \t\r") != std::string::npos) lines.push_back(line);
  }
  auto bad = [&](const std::string& why) {
    return Status::corruptData("bad " + info.string() + ": " + why);
  };
  if (lines.size() < 2) return bad("needs the scale on line 1 and max disparity on line 2");
  StereoGtCase c;
  std::istringstream s1(lines[0]);
  std::istringstream s2(lines[1]);
  std::string rest;
  if (!(s1 >> c.gt_scale) || (s1 >> rest) || !std::isfinite(c.gt_scale) || !(c.gt_scale > 0)) {
    return bad("line 1 '" + lines[0] + "' is not a scale > 0");
  }
  if (!(s2 >> c.max_disp) || (s2 >> rest) || c.max_disp <= 0) {
    return bad("line 2 '" + lines[1] + "' is not a max disparity > 0");
  }
  const fs::path mask = dir / (mask_kind + ".png");
  if (!isFile(mask)) return missing(mask);
  c.name = folderName(dir);
  c.left = (dir / "imL.png").string();
  c.right = (dir / "imR.png").string();
  c.gt = (dir / "groundtruth.png").string();
  c.mask = mask.string();
  return c;
}

// First existing <prefix><tag>.png / .jpg / .jpeg, or "".
std::string findView(const fs::path& dir, const std::string& prefix, const std::string& tag) {
  for (const char* ext : {".png", ".jpg", ".jpeg", ".ppm", ".pgm"}) {
    const fs::path p = dir / (prefix + tag + ext);
    if (isFile(p)) return p.string();
  }
  return {};
}

Result<StereoGtCase> middlebury2006(const fs::path& dir, const std::vector<std::string>& gt_files,
                                    const std::string& frame) {
  std::string prefix;
  if (!frame.empty()) {
    const std::string want = frame + "GT.png";
    if (std::find(gt_files.begin(), gt_files.end(), want) == gt_files.end()) {
      return missing(dir / want);
    }
    prefix = frame;
  } else {
    prefix = gt_files.front().substr(0, gt_files.front().size() - 6);
  }
  StereoGtCase c;
  c.name = folderName(dir);
  c.left = findView(dir, prefix, "L");
  c.right = findView(dir, prefix, "R");
  if (c.left.empty()) return missing(dir / (prefix + "L.png|jpg"));
  if (c.right.empty()) return missing(dir / (prefix + "R.png|jpg"));
  c.gt = (dir / (prefix + "GT.png")).string();
  c.gt_scale = 1.0;
  Result<ImageF32> gt = loadDisparity(c.gt, c.gt_scale);
  if (!gt.isOk()) return gt.status();
  float max_d = -1.0f;
  for (int y = 0; y < gt->height(); ++y) {
    const float* row = gt->row(y);
    for (int x = 0; x < gt->width(); ++x) {
      if (std::isfinite(row[x])) max_d = std::max(max_d, row[x]);
    }
  }
  if (max_d < 0.0f) return Status::corruptData("ground truth " + c.gt + " has no known disparity");
  const int bound = static_cast<int>(std::ceil(max_d)) + 1;
  c.max_disp = (bound + 15) / 16 * 16;
  return c;
}

struct KittiDirs {
  const char* left;
  const char* right;
  const char* noc;
  const char* occ;
};

Result<StereoGtCase> kitti(const fs::path& dir, const KittiDirs& k, const std::string& mask_kind,
                           const std::string& frame) {
  if (mask_kind == "disc") {
    return Status::invalidArgument("KITTI has no discontinuity mask (use nonocc or all): " +
                                   dir.string());
  }
  const fs::path gt_dir = dir / (mask_kind == "all" ? k.occ : k.noc);
  if (!isDir(gt_dir))
    return Status::notFound("KITTI ground-truth folder does not exist: " + gt_dir.string());
  std::string file;
  if (frame.empty()) {
    for (const std::string& f : listFiles(dir / k.left)) {
      if (endsWith(f, ".png") && isFile(gt_dir / f)) {
        file = f;
        break;
      }
    }
    if (file.empty()) {
      return Status::notFound("no left image in " + (dir / k.left).string() +
                              " has ground truth in " + gt_dir.string());
    }
  } else {
    file = frame;
    if (!endsWith(file, ".png")) {
      if (file.size() == 6 && std::all_of(file.begin(), file.end(),
                                          [](unsigned char ch) { return std::isdigit(ch) != 0; }))
        file += "_10";
      file += ".png";
    }
  }
  StereoGtCase c;
  const fs::path left = dir / k.left / file;
  const fs::path right = dir / k.right / file;
  const fs::path gt = gt_dir / file;
  for (const fs::path& p : {left, right, gt}) {
    if (!isFile(p)) return missing(p);
  }
  c.name = folderName(dir) + "_" + file.substr(0, file.size() - 4);
  c.left = left.string();
  c.right = right.string();
  c.gt = gt.string();
  c.gt_scale = 256.0;
  Result<ImageU8> img = loadGrey(c.left);
  if (!img.isOk()) return img.status();
  if (img->width() < 2) return Status::corruptData("KITTI image too narrow: " + c.left);
  c.max_disp = std::min(256, img->width() - 1);
  return c;
}

}  // namespace

Result<StereoGtCase> findStereoGtCase(const std::string& dir_str, const std::string& mask_kind,
                                      const std::string& frame) {
  const fs::path dir(dir_str);
  std::error_code ec;
  if (!fs::exists(dir, ec))
    return Status::notFound("stereo dataset folder does not exist: " + dir_str);
  if (!isDir(dir)) return Status::invalidArgument("not a folder: " + dir_str);
  if (mask_kind != "nonocc" && mask_kind != "all" && mask_kind != "disc") {
    return Status::invalidArgument("mask kind '" + mask_kind +
                                   "' is not one of nonocc, all, disc (for " + dir_str + ")");
  }

  if (isFile(dir / "imL.png") && isFile(dir / "imR.png") && isFile(dir / "groundtruth.png") &&
      isFile(dir / "info.txt")) {
    return middleburyV2(dir, mask_kind);
  }
  static constexpr KittiDirs kKitti2012{"image_0", "image_1", "disp_noc", "disp_occ"};
  static constexpr KittiDirs kKitti2015{"image_2", "image_3", "disp_noc_0", "disp_occ_0"};
  for (const KittiDirs& k : {kKitti2012, kKitti2015}) {
    if (isDir(dir / k.left) && isDir(dir / k.right) && (isDir(dir / k.noc) || isDir(dir / k.occ))) {
      return kitti(dir, k, mask_kind, frame);
    }
  }
  std::vector<std::string> gt_files;
  for (const std::string& f : listFiles(dir)) {
    if (endsWith(f, "GT.png") && f.size() > 6) gt_files.push_back(f);
  }
  if (!gt_files.empty()) return middlebury2006(dir, gt_files, frame);

  return Status::notFound(
      "no stereo ground-truth layout recognised in " + dir_str +
      "; expected one of: Middlebury v2 (imL.png, imR.png, groundtruth.png, info.txt, "
      "nonocc.png/all.png/disc.png), Middlebury 2006 (<name>L.png|jpg, <name>R.png|jpg, "
      "<name>GT.png), KITTI stereo 2012 (image_0/, image_1/, disp_noc/ or disp_occ/) or 2015 "
      "(image_2/, image_3/, disp_noc_0/ or disp_occ_0/)");
}

}  // namespace svslam::drivers
