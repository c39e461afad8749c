// Stereo calibration file read / write (see stereo_calibration_file.hpp).
#include "drivers/files/stereo_calibration_file.hpp"

#include <cstdio>
#include <filesystem>
#include <system_error>

namespace svslam::drivers {
namespace {

Result<cv::Mat> readMatrix(const cv::FileStorage& fs, const std::string& key,
                           const std::string& file, int rows, int cols) {
  cv::Mat m;
  const cv::FileNode node = fs[key];
  if (node.empty()) return Status::corruptData(file + ": missing calibration key '" + key + "'");
  node >> m;
  if (m.empty() && !(key[0] == 'D'))
    return Status::corruptData(file + ": key '" + key + "' is not a matrix");
  if (!m.empty()) m.convertTo(m, CV_64F);
  if (rows > 0 && (m.rows * m.cols != rows * cols))
    return Status::corruptData(file + ": key '" + key + "' must have " +
                               std::to_string(rows * cols) + " elements, has " +
                               std::to_string(m.rows * m.cols));
  if (rows > 0) m = m.reshape(1, rows);
  if (!m.empty() && !cv::checkRange(m))
    return Status::corruptData(file + ": key '" + key + "' contains NaN or infinity");
  return m;
}

}  // namespace

Result<StereoCalibrationFile> readStereoCalibrationFile(const std::string& file) {
  try {
    cv::FileStorage fs(file, cv::FileStorage::READ);
    if (!fs.isOpened()) return Status::notFound("cannot open calibration file " + file);
    StereoCalibrationFile c;
    cv::Mat* K[2] = {&c.K1, &c.K2};
    cv::Mat* D[2] = {&c.D1, &c.D2};
    for (int i = 0; i < 2; ++i) {
      const std::string n = std::to_string(i + 1);
      auto k = readMatrix(fs, "K" + n, file, 3, 3);
      if (!k) return k.status();
      auto d = readMatrix(fs, "D" + n, file, 0, 0);
      if (!d) return d.status();
      *K[i] = *k;
      *D[i] = d->empty() ? cv::Mat::zeros(1, 5, CV_64F) : d->reshape(1, 1);
      if (!(K[i]->at<double>(0, 0) > 0 && K[i]->at<double>(1, 1) > 0))
        return Status::corruptData(file + ": key 'K" + n + "' has focal lengths <= 0");
    }
    auto R = readMatrix(fs, "R", file, 3, 3);
    if (!R) return R.status();
    auto T = readMatrix(fs, "T", file, 3, 1);
    if (!T) return T.status();
    c.R = *R;
    c.T = *T;
    int* size[2] = {&c.width, &c.height};
    const char* size_keys[2] = {"image_width", "image_height"};
    for (int i = 0; i < 2; ++i) {
      const cv::FileNode node = fs[size_keys[i]];
      if (node.empty() || !node.isInt())
        return Status::corruptData(file + ": missing calibration key '" + size_keys[i] + "'");
      *size[i] = static_cast<int>(node);
    }
    return c;
  } catch (const cv::Exception& e) {
    return Status::corruptData(file + ": cannot read calibration: " + e.what());
  }
}

Status writeStereoCalibrationFile(const std::string& file, const StereoCalibrationFile& c) {
  namespace fs = std::filesystem;
  const fs::path target(file);
  // The temporary keeps the extension: FileStorage picks the format from it.
  const fs::path tmp = target.parent_path() / (".tmp-" + target.filename().string());
  std::error_code ec;
  try {
    cv::FileStorage out(tmp.string(), cv::FileStorage::WRITE);
    if (!out.isOpened()) return Status::ioError("cannot write calibration file " + file);
    out << "K1" << c.K1 << "D1" << c.D1 << "K2" << c.K2 << "D2" << c.D2 << "R" << c.R << "T" << c.T
        << "image_width" << c.width << "image_height" << c.height;
    out.release();
  } catch (const cv::Exception& e) {
    fs::remove(tmp, ec);
    return Status::ioError("cannot write calibration file " + file + ": " + e.what());
  }
  fs::rename(tmp, target, ec);
  if (ec) {
    fs::remove(tmp, ec);
    return Status::ioError("cannot write calibration file " + file + ": " + ec.message());
  }
  return Status::ok();
}

}  // namespace svslam::drivers
