// kitti:DIR source (see stereo_source.hpp).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include "drivers/files/image_io.hpp"
#include "drivers/source/stereo_source.hpp"

namespace fs = std::filesystem;

namespace svslam::drivers {
namespace {

std::vector<std::string> listImages(const fs::path& dir) {
  std::vector<std::string> out;
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string ext = e.path().extension().string();
    if (e.is_regular_file() && (ext == ".png" || ext == ".jpg" || ext == ".pgm"))
      out.push_back(e.path().string());
  }
  std::sort(out.begin(), out.end());
  return out;
}

class KittiSource final : public StereoSource {
 public:
  KittiSource(StereoCalibration c, std::vector<std::string> l, std::vector<std::string> r,
              std::vector<TimeNs> t)
      : calib_(c), left_(std::move(l)), right_(std::move(r)), t_ns_(std::move(t)) {}
  const StereoCalibration& calibration() const override { return calib_; }
  int size() const override { return static_cast<int>(left_.size()); }
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
  auto left = listImages(ldir), right = listImages(rdir);
  if (left.empty()) return Status::notFound("no image in " + ldir.string());
  if (left.size() != right.size())
    return Status::corruptData("KITTI folder " + dir + ": " + std::to_string(left.size()) +
                               " left but " + std::to_string(right.size()) + " right images");
  // calib.txt: P0 then P1, 12 numbers each, optionally labelled "P0:".
  const fs::path calib_path = d / "calib.txt";
  std::ifstream cf(calib_path);
  if (!cf) return Status::notFound("cannot open " + calib_path.string());
  std::vector<std::vector<double>> P;
  std::string line;
  while (std::getline(cf, line) && P.size() < 2) {
    std::istringstream s(line);
    std::string first;
    if (!(s >> first)) continue;
    std::vector<double> v;
    if (first.back() != ':') s.seekg(0);
    double x;
    while (s >> x) v.push_back(x);
    if (v.size() != 12)
      return Status::corruptData(calib_path.string() + ": a projection line needs 12 numbers");
    P.push_back(v);
  }
  if (P.size() < 2) return Status::corruptData(calib_path.string() + ": needs the P0 and P1 lines");
  auto first = loadGrey(left[0]);
  if (!first) return first.status();
  StereoCalibration c;
  c.f_px = P[0][0];
  c.cx_px = P[0][2];
  c.cy_px = P[0][6];
  c.baseline_m = P[1][0] != 0 ? -P[1][3] / P[1][0] : NAN;
  c.width = first->width();
  c.height = first->height();
  if (Status s = c.validate(); !s)
    return Status(s.code(), calib_path.string() + ": " + s.message());
  // times.txt (seconds) when present, else 10 Hz.
  std::vector<TimeNs> t;
  std::ifstream tf(d / "times.txt");
  if (tf) {
    double ts;
    while (tf >> ts) t.push_back(secondsToNs(ts));
    if (t.size() != left.size())
      return Status::corruptData((d / "times.txt").string() + ": " + std::to_string(t.size()) +
                                 " stamps for " + std::to_string(left.size()) + " frames");
  } else {
    for (std::size_t i = 0; i < left.size(); ++i)
      t.push_back(static_cast<TimeNs>(i) * 100 * kNsPerMs);
  }
  return std::unique_ptr<StereoSource>(
      std::make_unique<KittiSource>(c, std::move(left), std::move(right), std::move(t)));
}

}  // namespace svslam::drivers
