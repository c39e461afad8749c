// euroc:DIR source (see stereo_source.hpp): raw distorted pairs rectified with OpenCV.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <vector>

#include "drivers/datasets/dataset_files.hpp"
#include "drivers/files/image_io.hpp"
#include "drivers/files/opencv_view.hpp"
#include "drivers/files/trajectory_io.hpp"
#include "drivers/files/yaml_lists.hpp"
#include "drivers/source/stereo_source.hpp"

namespace fs = std::filesystem;

namespace svslam::drivers {
namespace {

struct EurocCamera {
  cv::Mat K, D;
  cv::Size size;
  Eigen::Isometry3d T_BS;
  std::vector<TimeNs> t_ns;
  std::vector<std::string> files;
};

// The camera model and extrinsic of cam_dir/sensor.yaml (no image list).
Result<EurocCamera> readCameraModel(const fs::path& cam_dir) {
  const std::string yaml = (cam_dir / "sensor.yaml").string();
  auto yaml_text = readTextFile(yaml);
  if (!yaml_text) return yaml_text.status();
  auto sensor = parseEurocSensor(*yaml_text, yaml);
  if (!sensor) return sensor.status();
  const auto& k = sensor->intrinsics;
  const auto& d = sensor->distortion;
  EurocCamera c;
  c.K = (cv::Mat_<double>(3, 3) << k[0], 0, k[2], 0, k[1], k[3], 0, 0, 1);
  c.D = (cv::Mat_<double>(1, 4) << d[0], d[1], d[2], d[3]);
  c.size = cv::Size(sensor->width, sensor->height);
  c.T_BS = sensor->T_BS;
  return c;
}

Result<EurocCamera> readCamera(const fs::path& cam_dir) {
  auto model = readCameraModel(cam_dir);
  if (!model) return model.status();
  EurocCamera c = std::move(model).value();
  const std::string csv = (cam_dir / "data.csv").string();
  auto csv_text = readTextFile(csv);
  if (!csv_text) return csv_text.status();
  auto list = parseEurocDataCsv(*csv_text, csv);
  if (!list) return list.status();
  c.t_ns = std::move(list->t_ns);
  for (const std::string& name : list->names) c.files.push_back((cam_dir / "data" / name).string());
  return c;
}

struct Rectification {
  cv::Mat R0, R1, P0, P1;  // cv::stereoRectify's (p_rect0 = R0 p_cam0), zero disparity, alpha 0
};

// The rectification of the pair of folder dir (named in the error when the sizes differ).
Result<Rectification> rectify(const EurocCamera& c0, const EurocCamera& c1, const std::string& dir) {
  if (c0.size != c1.size)
    return Status::corruptData("EuRoC cam0 and cam1 resolutions differ in " + dir);
  // p_cam1 = R p_cam0 + T with T_cam1_cam0 = T_BS1^-1 T_BS0.
  const Eigen::Isometry3d T10 = c1.T_BS.inverse() * c0.T_BS;
  cv::Mat R(3, 3, CV_64F), T(3, 1, CV_64F);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) R.at<double>(r, c) = T10.linear()(r, c);
    T.at<double>(r, 0) = T10.translation()(r);
  }
  Rectification out;
  cv::Mat Q;
  cv::stereoRectify(c0.K, c0.D, c1.K, c1.D, c0.size, R, T, out.R0, out.R1, out.P0, out.P1, Q,
                    cv::CALIB_ZERO_DISPARITY, 0.0);
  return out;
}

class EurocSource final : public StereoSource {
 public:
  EurocSource(EurocCamera c0, EurocCamera c1, StereoCalibration calib, cv::Mat m0x, cv::Mat m0y,
              cv::Mat m1x, cv::Mat m1y)
      : c0_(std::move(c0)),
        c1_(std::move(c1)),
        calib_(calib),
        m0x_(m0x),
        m0y_(m0y),
        m1x_(m1x),
        m1y_(m1y) {}
  const StereoCalibration& calibration() const override { return calib_; }
  int size() const override { return static_cast<int>(c0_.files.size()); }
  Result<bool> next(StereoFrame& out) override {
    if (pos_ >= c0_.files.size()) return false;
    for (int side = 0; side < 2; ++side) {
      const std::string& path = side == 0 ? c0_.files[pos_] : c1_.files[pos_];
      auto raw = loadGrey(path);
      if (!raw) return raw.status();
      if (raw->width() != c0_.size.width || raw->height() != c0_.size.height)
        return Status::corruptData(path + ": image size differs from sensor.yaml's resolution");
      ImageU8& dst = side == 0 ? out.left : out.right;
      dst.resize(calib_.width, calib_.height);
      cv::Mat dst_mat = asMat(dst);
      cv::remap(asMat(*raw), dst_mat, side == 0 ? m0x_ : m1x_, side == 0 ? m0y_ : m1y_,
                cv::INTER_LINEAR);
    }
    out.index = static_cast<int>(pos_);
    out.t_ns = c0_.t_ns[pos_];
    ++pos_;
    return true;
  }

 private:
  EurocCamera c0_, c1_;
  StereoCalibration calib_;
  cv::Mat m0x_, m0y_, m1x_, m1y_;
  std::size_t pos_ = 0;
};

}  // namespace

Result<EurocSensor> parseEurocSensor(const std::string& text, const std::string& file) {
  auto intr = yamlNumberList(text, "", "intrinsics", file);
  if (!intr) return intr.status();
  auto dist = yamlNumberList(text, "", "distortion_coefficients", file);
  if (!dist) return dist.status();
  auto res = yamlNumberList(text, "", "resolution", file);
  if (!res) return res.status();
  auto tbs = parseEurocTbs(text, file);
  if (!tbs) return tbs.status();
  if (intr->size() != 4 || dist->size() != 4 || res->size() != 2)
    return Status::corruptData(
        file +
        ": expected intrinsics [fu fv cu cv], 4 distortion coefficients and resolution [w h]");
  EurocSensor s;
  std::copy(intr->begin(), intr->end(), s.intrinsics.begin());
  std::copy(dist->begin(), dist->end(), s.distortion.begin());
  // Checked before the conversion: a double out of int's range converts with undefined behaviour.
  for (double side : *res)
    if (!(side >= 1.0 && side <= 65536.0) || side != std::floor(side))
      return Status::corruptData(file + ": resolution must be two integers in [1, 65536]");
  s.width = static_cast<int>((*res)[0]);
  s.height = static_cast<int>((*res)[1]);
  if (s.intrinsics[0] <= 0 || s.intrinsics[1] <= 0)
    return Status::corruptData(file + ": focal lengths must be > 0");
  s.T_BS = *tbs;
  return s;
}

Result<EurocImageList> parseEurocDataCsv(const std::string& text, const std::string& file) {
  std::istringstream f(text);
  EurocImageList out;
  std::string line;
  int line_no = 0;
  while (std::getline(f, line)) {
    ++line_no;
    if (line.empty() || line[0] == '#') continue;
    const auto comma = line.find(',');
    if (comma == std::string::npos)
      return Status::corruptData(file + ":" + std::to_string(line_no) +
                                 ": expected 'timestamp,filename'");
    std::string name = line.substr(comma + 1);
    while (!name.empty() && (name.back() == '\r' || name.back() == ' ')) name.pop_back();
    try {
      out.t_ns.push_back(std::stoll(line.substr(0, comma)));
    } catch (const std::exception&) {
      return Status::corruptData(file + ":" + std::to_string(line_no) + ": bad timestamp");
    }
    out.names.push_back(name);
  }
  if (out.names.empty()) return Status::corruptData(file + ": no image listed");
  return out;
}

Result<std::unique_ptr<StereoSource>> openEurocSource(const std::string& dir) {
  const fs::path mav = fs::path(dir) / "mav0";
  if (!fs::is_directory(mav / "cam0") || !fs::is_directory(mav / "cam1"))
    return Status::notFound("EuRoC folder " + dir + " has no mav0/cam0 and mav0/cam1");
  auto c0 = readCamera(mav / "cam0");
  if (!c0) return c0.status();
  auto c1 = readCamera(mav / "cam1");
  if (!c1) return c1.status();
  if (c0->t_ns != c1->t_ns)
    return Status::corruptData("EuRoC cam0 and cam1 list different timestamps in " + dir);
  auto rect = rectify(*c0, *c1, dir);
  if (!rect) return rect.status();
  const cv::Mat &R0 = rect->R0, &R1 = rect->R1, &P0 = rect->P0, &P1 = rect->P1;
  cv::Mat m0x, m0y, m1x, m1y;
  cv::initUndistortRectifyMap(c0->K, c0->D, R0, P0, c0->size, CV_16SC2, m0x, m0y);
  cv::initUndistortRectifyMap(c1->K, c1->D, R1, P1, c1->size, CV_16SC2, m1x, m1y);
  StereoCalibration calib;
  calib.f_px = P0.at<double>(0, 0);
  calib.cx_px = P0.at<double>(0, 2);
  calib.cy_px = P0.at<double>(1, 2);
  calib.baseline_m = -P1.at<double>(0, 3) / P1.at<double>(0, 0);
  calib.width = c0->size.width;
  calib.height = c0->size.height;
  if (Status s = checkStereoCalibration(calib); !s)
    return Status(s.code(), "EuRoC rectification of " + dir + ": " + s.message());
  return std::unique_ptr<StereoSource>(std::make_unique<EurocSource>(
      std::move(c0).value(), std::move(c1).value(), calib, m0x, m0y, m1x, m1y));
}

Result<Eigen::Isometry3d> eurocBodyToRectifiedLeft(const std::string& dir) {
  const fs::path mav = fs::path(dir) / "mav0";
  auto c0 = readCameraModel(mav / "cam0");
  if (!c0) return c0.status();
  auto c1 = readCameraModel(mav / "cam1");
  if (!c1) return c1.status();
  auto rect = rectify(*c0, *c1, dir);
  if (!rect) return rect.status();
  Eigen::Isometry3d T_cam0_rect = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) T_cam0_rect.linear()(r, c) = rect->R0.at<double>(c, r);  // R0^T
  if (!T_cam0_rect.matrix().allFinite())
    return Status::corruptData("EuRoC rectification of " + dir + " is not finite");
  return c0->T_BS * T_cam0_rect;
}

}  // namespace svslam::drivers
