// kitti:DIR source (see stereo_source.hpp).
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <vector>

#include "drivers/datasets/dataset_files.hpp"
#include "drivers/files/image_io.hpp"
#include "drivers/source/stereo_source.hpp"

namespace fs = std::filesystem;

namespace svslam::drivers {
namespace {

// The images of `dir` by name without extension (regular .png/.jpg/.pgm files; names starting
// with '.' are hidden files, not images). Two images with the same name are an error.
Result<std::map<std::string, std::string>> listImages(const fs::path& dir) {
  std::map<std::string, std::string> out;
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    const std::string ext = e.path().extension().string();
    if (name.empty() || name[0] == '.' || !e.is_regular_file()) continue;
    if (ext != ".png" && ext != ".jpg" && ext != ".pgm") continue;
    const std::string stem = e.path().stem().string();
    if (auto it = out.find(stem); it != out.end())
      return Status::corruptData("two images of frame '" + stem + "' in " + dir.string() + ": " +
                                 fs::path(it->second).filename().string() + " and " + name);
    out.emplace(stem, e.path().string());
  }
  return out;
}

// Whitespace-separated numbers of `line`; `what` names the line in errors.
Result<std::vector<double>> parseNumbers(const std::string& line, const std::string& what) {
  std::istringstream s(line);
  std::vector<double> v;
  std::string tok;
  while (s >> tok) {
    char* end = nullptr;
    const double x = std::strtod(tok.c_str(), &end);  // overflow gives +-inf
    if (end == tok.c_str() || *end != '\0')
      return Status::corruptData(what + ": '" + tok + "' is not a number");
    if (!std::isfinite(x)) return Status::corruptData(what + ": value '" + tok + "' is not finite");
    v.push_back(x);
  }
  return v;
}

// The whole of a small text file, or notFound naming it.
Result<std::string> readText(const fs::path& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) return Status::notFound("cannot open " + path.string());
  std::ostringstream ss;
  ss << f.rdbuf();
  if (f.bad()) return Status::ioError("cannot read " + path.string());
  return ss.str();
}

}  // namespace

Result<StereoCalibration> parseKittiCalibration(const std::string& text, const std::string& file) {
  std::istringstream cf(text);
  std::vector<std::vector<double>> P;
  std::string line;
  int line_no = 0;
  while (P.size() < 2 && std::getline(cf, line)) {
    ++line_no;
    std::istringstream s(line);
    std::string first;
    if (!(s >> first)) continue;
    const std::string where = file + ":" + std::to_string(line_no);
    auto v = parseNumbers(first.back() == ':' ? line.substr(line.find(':') + 1) : line, where);
    if (!v) return v.status();
    if (v->size() != 12)
      return Status::corruptData(where + ": a projection line needs 12 numbers, got " +
                                 std::to_string(v->size()));
    P.push_back(std::move(*v));
  }
  if (P.size() < 2) return Status::corruptData(file + ": needs the P0 and P1 lines");
  if (!(P[0][0] > 0.0))
    return Status::corruptData(file + ": P0 fx (its 1st number) must be positive, got " +
                               std::to_string(P[0][0]));
  const char* names[] = {"fx", "cx", "fy", "cy"};
  const int at[] = {0, 2, 5, 6};
  for (int k = 0; k < 4; ++k) {
    const double a = P[0][static_cast<std::size_t>(at[k])],
                 b = P[1][static_cast<std::size_t>(at[k])];
    if (std::abs(a - b) > 1e-6 * std::max(1.0, std::abs(a))) {
      std::ostringstream ss;
      ss << file << ": P1 " << names[k] << " = " << b << " differs from P0's " << a
         << " (a rectified pair needs the same intrinsics in P0 and P1)";
      return Status::corruptData(ss.str());
    }
  }
  StereoCalibration c;
  c.f_px = P[0][0];
  c.cx_px = P[0][2];
  c.cy_px = P[0][6];
  c.baseline_m = -P[1][3] / P[1][0];
  return c;
}

Result<std::vector<TimeNs>> parseKittiTimes(const std::string& text, const std::string& file) {
  std::istringstream tf(text);
  std::vector<TimeNs> t;
  std::string line;
  int line_no = 0;
  double last = 0;
  while (std::getline(tf, line)) {
    ++line_no;
    const std::string where = file + ":" + std::to_string(line_no);
    auto v = parseNumbers(line, where);
    if (!v) return v.status();
    if (v->empty()) continue;
    if (v->size() != 1)
      return Status::corruptData(where + ": expected one time stamp (seconds) per line");
    const double ts = (*v)[0];
    if (!(std::abs(ts) < 9.2e9))  // int64 nanoseconds hold +-9.22e9 s
      return Status::corruptData(where + ": time stamp " + std::to_string(ts) +
                                 " s is out of range (|t| < 9.2e9 s)");
    if (!t.empty() && !(ts > last))
      return Status::corruptData(where + ": time stamp " + std::to_string(ts) +
                                 " s is not after the previous one (" + std::to_string(last) +
                                 " s)");
    t.push_back(secondsToNs(ts));
    last = ts;
  }
  return t;
}

namespace {

class KittiSource final : public StereoSource {
 public:
  KittiSource(StereoCalibration c, std::vector<std::string> l, std::vector<std::string> r,
              std::vector<TimeNs> t, std::vector<std::string> skipped)
      : calib_(c),
        left_(std::move(l)),
        right_(std::move(r)),
        t_ns_(std::move(t)),
        skipped_(std::move(skipped)) {}
  const StereoCalibration& calibration() const override { return calib_; }
  int size() const override { return static_cast<int>(left_.size()); }
  int skippedFrames() const override { return static_cast<int>(skipped_.size()); }
  std::string skippedFramesDetail() const override {
    std::string s;
    for (std::size_t i = 0; i < skipped_.size() && i < 10; ++i) s += (i ? ", " : "") + skipped_[i];
    if (skipped_.size() > 10) s += ", ...";
    return s;
  }
  Result<bool> next(StereoFrame& out) override {
    if (pos_ >= left_.size()) return false;
    auto l = loadGrey(left_[pos_]);
    if (!l) return l.status();
    auto r = loadGrey(right_[pos_]);
    if (!r) return r.status();
    if (l->width() != calib_.width || l->height() != calib_.height || r->width() != calib_.width ||
        r->height() != calib_.height)
      return Status::corruptData("image size differs from the first frame's in " + left_[pos_] +
                                 " / " + right_[pos_]);
    out.index = static_cast<int>(pos_);
    out.t_ns = t_ns_[pos_];
    out.left = std::move(l).value();
    out.right = std::move(r).value();
    ++pos_;
    return true;
  }

 private:
  StereoCalibration calib_;
  std::vector<std::string> left_, right_;
  std::vector<TimeNs> t_ns_;
  std::vector<std::string> skipped_;  // e.g. "000003 (no right image)"
  std::size_t pos_ = 0;
};

}  // namespace

Result<std::unique_ptr<StereoSource>> openKittiSource(const std::string& dir) {
  const fs::path d(dir);
  if (!fs::is_directory(d)) return Status::notFound("KITTI folder does not exist: " + dir);
  fs::path ldir = d / "image_0", rdir = d / "image_1";
  if (!fs::is_directory(ldir)) {
    ldir = d / "image_l";
    rdir = d / "image_r";
  }
  if (!fs::is_directory(ldir) || !fs::is_directory(rdir))
    return Status::notFound("KITTI folder " + dir +
                            " has neither image_0/ + image_1/ nor image_l/ + image_r/");
  auto lmap = listImages(ldir);
  if (!lmap) return lmap.status();
  auto rmap = listImages(rdir);
  if (!rmap) return rmap.status();
  if (lmap->empty()) return Status::notFound("no image in " + ldir.string());
  // Frames by name, in name order: a pair is the left and right images of the same name.
  std::map<std::string, int> names;  // name -> 1 left only, 2 right only, 3 both
  for (const auto& [name, path] : *lmap) names[name] |= 1;
  for (const auto& [name, path] : *rmap) names[name] |= 2;
  std::vector<std::string> left, right, skipped;
  std::vector<bool> kept;
  for (const auto& [name, sides] : names) {
    kept.push_back(sides == 3);
    if (sides == 3) {
      left.push_back(lmap->at(name));
      right.push_back(rmap->at(name));
    } else {
      skipped.push_back(name + (sides == 1 ? " (no right image)" : " (no left image)"));
    }
  }
  if (left.empty())
    return Status::notFound("KITTI folder " + dir + ": no frame has both a left and a right image");

  auto calib_text = readText(d / "calib.txt");
  if (!calib_text) return calib_text.status();
  auto calib = parseKittiCalibration(*calib_text, (d / "calib.txt").string());
  if (!calib) return calib.status();
  auto first = loadGrey(left[0]);
  if (!first) return first.status();
  StereoCalibration c = *calib;
  c.width = first->width();
  c.height = first->height();
  if (Status s = checkStereoCalibration(c); !s)
    return Status(s.code(), (d / "calib.txt").string() + ": " + s.message());
  // times.txt (seconds; one per frame name found in either folder) when present, else 10 Hz.
  std::vector<TimeNs> t;
  if (fs::exists(d / "times.txt")) {
    auto times_text = readText(d / "times.txt");
    if (!times_text) return times_text.status();
    auto all = parseKittiTimes(*times_text, (d / "times.txt").string());
    if (!all) return all.status();
    if (all->size() != names.size())
      return Status::corruptData((d / "times.txt").string() + ": " + std::to_string(all->size()) +
                                 " stamps for " + std::to_string(names.size()) + " frames");
    for (std::size_t i = 0; i < kept.size(); ++i)
      if (kept[i]) t.push_back((*all)[i]);
  } else {
    for (std::size_t i = 0; i < kept.size(); ++i)
      if (kept[i]) t.push_back(static_cast<TimeNs>(i) * 100 * kNsPerMs);
  }
  return std::unique_ptr<StereoSource>(std::make_unique<KittiSource>(
      c, std::move(left), std::move(right), std::move(t), std::move(skipped)));
}

}  // namespace svslam::drivers
