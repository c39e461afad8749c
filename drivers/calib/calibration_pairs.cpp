// Calibration image pairs on disk (see calibration_pairs.hpp).
#include "drivers/calib/calibration_pairs.hpp"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <map>

namespace svslam::drivers {
namespace {

namespace fs = std::filesystem;

bool isImageName(const fs::path& p) {
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  for (const char* e : {".png", ".jpg", ".jpeg", ".pgm", ".ppm", ".bmp", ".tif", ".tiff"})
    if (ext == e) return true;
  return false;
}

// Image file names of `dir` (not paths).
Result<std::vector<std::string>> imageNames(const std::string& dir) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return Status::notFound("no such folder: " + dir);
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir, ec))
    if (e.is_regular_file(ec) && isImageName(e.path()))
      names.push_back(e.path().filename().string());
  if (ec) return Status::ioError("cannot list " + dir + ": " + ec.message());
  return names;
}

// Pairs keys present on both sides; an unmatched key is an error naming it.
Result<std::vector<CalibrationPairPaths>> match(const std::map<std::string, std::string>& left,
                                                const std::map<std::string, std::string>& right,
                                                const std::string& where,
                                                const std::string& left_prefix,
                                                const std::string& right_prefix) {
  std::vector<CalibrationPairPaths> out;
  std::string unmatched;
  for (const auto& [key, path] : left) {
    auto it = right.find(key);
    if (it == right.end()) {
      if (unmatched.empty()) unmatched = left_prefix + key + " has no " + right_prefix + key;
      continue;
    }
    out.push_back({key, path, it->second});
  }
  for (const auto& [key, path] : right)
    if (!left.count(key) && unmatched.empty())
      unmatched = right_prefix + key + " has no " + left_prefix + key;
  if (!unmatched.empty())
    return Status::invalidArgument("unequal left/right images in " + where + ": " +
                                   std::to_string(left.size()) + " left and " +
                                   std::to_string(right.size()) + " right; " + unmatched);
  if (out.empty()) return Status::invalidArgument("no left/right image pair in " + where);
  return out;
}

}  // namespace

Result<std::vector<CalibrationPairPaths>> listCalibrationPairs(const std::string& dir) {
  auto names = imageNames(dir);
  if (!names) return names.status();
  std::map<std::string, std::string> left, right;
  for (const std::string& n : *names) {
    if (n.rfind("left", 0) == 0) left[n.substr(4)] = (fs::path(dir) / n).string();
    if (n.rfind("right", 0) == 0) right[n.substr(5)] = (fs::path(dir) / n).string();
  }
  if (left.empty() && right.empty())
    return Status::invalidArgument("no left*/right* images in " + dir);
  return match(left, right, dir, "left", "right");
}

Result<std::vector<CalibrationPairPaths>> listCalibrationPairs(const std::string& left_dir,
                                                               const std::string& right_dir) {
  std::map<std::string, std::string> side[2];
  const std::string* dirs[2] = {&left_dir, &right_dir};
  for (int i = 0; i < 2; ++i) {
    auto names = imageNames(*dirs[i]);
    if (!names) return names.status();
    for (const std::string& n : *names) side[i][n] = (fs::path(*dirs[i]) / n).string();
  }
  return match(side[0], side[1], left_dir + " and " + right_dir, "left ", "right ");
}

}  // namespace svslam::drivers
