#pragma once
// Synthetic stereo views of a chessboard with known cameras, the independent reference of the
// calibration tests: each view is the board texture warped by the plane homography
// H = K [r1 r2 t] A (A: texture px -> board metres), so corners land exactly where
// cv::projectPoints puts them. Ideal pinhole cameras (no distortion), right camera at +x.
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

namespace svslam::test {

struct ChessboardScene {
  int cols = 9, rows = 6;                        // inner corners
  double square_m = 0.03;                        // m
  double fx = 500.0, fy = 500.0;                 // px
  double cx = 322.0, cy = 236.0;                 // px
  double baseline_m = 0.1;                       // right camera at +x
  int width = 640, height = 480;                 // px
  int dark = 40, light = 200, background = 120;  // grey levels

  cv::Mat K() const { return (cv::Mat_<double>(3, 3) << fx, 0, cx, 0, fy, cy, 0, 0, 1); }

  // Board pose i of a fixed, varied set (tilts up to ~25 deg, the board spread over the image).
  void pose(int i, cv::Mat& rvec, cv::Mat& tvec) const {
    const double rx = 0.4 * std::sin(1.3 * i + 0.5), ry = 0.4 * std::cos(0.9 * i),
                 rz = 0.15 * std::sin(2.1 * i);
    rvec = (cv::Mat_<double>(3, 1) << rx, ry, rz);
    cv::Mat R;
    cv::Rodrigues(rvec, R);
    // Board centre in the left camera: a 3x3 walk over the view, 0.7..0.85 m away; the middle
    // of the pair's views (left camera shifted by half the baseline) is what gets spread.
    const double z = 0.7 + 0.05 * (i % 4);
    const double u = (i % 3 - 1) * 0.2 * width, v = ((i / 3) % 3 - 1) * 0.2 * height;
    const cv::Mat centre = (cv::Mat_<double>(3, 1) << u * z / fx + baseline_m / 2, v * z / fy, z);
    const cv::Mat board_centre =
        (cv::Mat_<double>(3, 1) << (cols - 1) / 2.0 * square_m, (rows - 1) / 2.0 * square_m, 0.0);
    tvec = centre - R * board_centre;
  }

  // Renders camera `cam` (0 left, 1 right) of pose i; false when a corner is within 8 px of the
  // border (the pose set is meant to avoid that).
  bool render(int i, int cam, cv::Mat& out) const {
    cv::Mat rvec, tvec, R;
    pose(i, rvec, tvec);
    if (cam == 1) tvec = tvec + (cv::Mat_<double>(3, 1) << -baseline_m, 0, 0);
    cv::Rodrigues(rvec, R);
    std::vector<cv::Point3f> obj;
    for (int r = 0; r < rows; ++r)
      for (int c = 0; c < cols; ++c)
        obj.emplace_back(static_cast<float>(c * square_m), static_cast<float>(r * square_m), 0.f);
    std::vector<cv::Point2f> img;
    cv::projectPoints(obj, rvec, tvec, K(), cv::Mat(), img);
    for (const auto& p : img)
      if (p.x < 8 || p.y < 8 || p.x > width - 9 || p.y > height - 9) return false;
    // Texture: s px per square, one white square of margin around the (cols+1) x (rows+1)
    // squares; inner corner (c, r) sits at texture (m + s - 0.5 + c s, m + s - 0.5 + r s).
    const int s = 16, m = s;
    cv::Mat tex(2 * m + (rows + 1) * s, 2 * m + (cols + 1) * s, CV_8U, cv::Scalar(light));
    for (int r = 0; r <= rows; ++r)
      for (int c = 0; c <= cols; ++c)
        if ((r + c) % 2 == 0) tex(cv::Rect(m + c * s, m + r * s, s, s)).setTo(dark);
    const double k = square_m / s, o = -(m + s - 0.5) * k;
    const cv::Mat A = (cv::Mat_<double>(3, 3) << k, 0, o, 0, k, o, 0, 0, 1);
    cv::Mat Rt(3, 3, CV_64F);
    R.col(0).copyTo(Rt.col(0));
    R.col(1).copyTo(Rt.col(1));
    tvec.copyTo(Rt.col(2));
    const cv::Mat H = K() * Rt * A;
    cv::warpPerspective(tex, out, H, cv::Size(width, height), cv::INTER_LINEAR, cv::BORDER_CONSTANT,
                        cv::Scalar(background));
    cv::GaussianBlur(out, out, cv::Size(0, 0), 0.7);
    return true;
  }
};

}  // namespace svslam::test
