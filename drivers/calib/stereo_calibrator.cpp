// Chessboard stereo calibration (see stereo_calibrator.hpp).
#include "drivers/calib/stereo_calibrator.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

namespace svslam::drivers {
namespace {

constexpr int kGrid = 3;  // coverage grid cells per side

std::string sizeText(cv::Size s) {
  return std::to_string(s.width) + "x" + std::to_string(s.height);
}

// Variance of the 3x3 Laplacian inside the bounding box of `corners`, grey levels^2.
double sharpness(const cv::Mat& img, const std::vector<cv::Point2f>& corners) {
  cv::Rect box = cv::boundingRect(corners) & cv::Rect(0, 0, img.cols, img.rows);
  if (box.width < 3 || box.height < 3) box = cv::Rect(0, 0, img.cols, img.rows);
  cv::Mat lap;
  cv::Laplacian(img(box), lap, CV_64F, 3);
  cv::Scalar mean, stddev;
  cv::meanStdDev(lap, mean, stddev);
  return stddev[0] * stddev[0];
}

// Smallest distance between neighbouring corners along board rows and columns, px.
double minSpacing(const std::vector<cv::Point2f>& c, int cols, int rows) {
  double best = std::numeric_limits<double>::max();
  for (int r = 0; r < rows; ++r)
    for (int k = 0; k < cols; ++k) {
      const cv::Point2f p = c[static_cast<std::size_t>(r * cols + k)];
      if (k + 1 < cols)
        best = std::min(best, cv::norm(p - c[static_cast<std::size_t>(r * cols + k + 1)]));
      if (r + 1 < rows)
        best = std::min(best, cv::norm(p - c[static_cast<std::size_t>((r + 1) * cols + k)]));
    }
  return best;
}

bool detect(const cv::Mat& img, const StereoCalibrationParams& p, std::vector<cv::Point2f>& out) {
  const cv::Size board(p.board_cols, p.board_rows);
  out.clear();
  if (!cv::findChessboardCorners(img, board, out,
                                 cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE))
    return false;
  const int half =
      std::clamp(static_cast<int>(minSpacing(out, p.board_cols, p.board_rows) / 3.0), 2, 11);
  cv::cornerSubPix(img, out, cv::Size(half, half), cv::Size(-1, -1),
                   cv::TermCriteria(cv::TermCriteria::EPS | cv::TermCriteria::COUNT, 50, 1e-3));
  return true;
}

double meanMotion(const std::vector<cv::Point2f>& a, const std::vector<cv::Point2f>& b) {
  double sum = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) sum += cv::norm(a[i] - b[i]);
  return sum / static_cast<double>(a.size());
}

double coverage(const std::vector<std::vector<cv::Point2f>>& views, cv::Size size) {
  bool cell[kGrid][kGrid] = {};
  for (const auto& v : views)
    for (const cv::Point2f& p : v) {
      const int gx =
          std::clamp(static_cast<int>(p.x * kGrid / static_cast<float>(size.width)), 0, kGrid - 1);
      const int gy =
          std::clamp(static_cast<int>(p.y * kGrid / static_cast<float>(size.height)), 0, kGrid - 1);
      cell[gy][gx] = true;
    }
  int n = 0;
  for (const auto& row : cell)
    for (bool c : row) n += c ? 1 : 0;
  return n / static_cast<double>(kGrid * kGrid);
}

// One calibration over `views`: per-camera calibrateCamera, stereoCalibrate, per-view stereo RMS.
struct Solve {
  double rms_l = 0, rms_r = 0, rms_pair = 0;
  cv::Mat K1, D1, K2, D2, R, T, per_view;  // per_view: N x 2 RMS (left, right), px
  cv::Mat std_l;  // left camera: standard deviations of fx, fy, cx, cy, k1, ... (calibrateCamera)
};

Solve solve(const std::vector<std::vector<cv::Point3f>>& obj,
            const std::vector<std::vector<cv::Point2f>>& l,
            const std::vector<std::vector<cv::Point2f>>& r, cv::Size size, bool fix_intrinsic) {
  Solve s;
  std::vector<cv::Mat> rv, tv;
  const cv::TermCriteria crit(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 100, 1e-9);
  cv::Mat std_extrinsics, per_view_l;
  s.rms_l = cv::calibrateCamera(obj, l, size, s.K1, s.D1, rv, tv, s.std_l, std_extrinsics,
                                per_view_l, 0, crit);
  s.rms_r = cv::calibrateCamera(obj, r, size, s.K2, s.D2, rv, tv, 0, crit);
  cv::Mat E, F;
  s.rms_pair = cv::stereoCalibrate(
      obj, l, r, s.K1, s.D1, s.K2, s.D2, size, s.R, s.T, E, F, s.per_view,
      fix_intrinsic ? cv::CALIB_FIX_INTRINSIC : cv::CALIB_USE_INTRINSIC_GUESS, crit);
  return s;
}

}  // namespace

Status StereoCalibrationParams::validate() const {
  if (board_cols < 3 || board_cols > 100 || board_rows < 3 || board_rows > 100)
    return Status::invalidArgument("board must have 3..100 inner corners per side, got " +
                                   std::to_string(board_cols) + "x" + std::to_string(board_rows));
  if (!(square_m > 0.0 && square_m <= 10.0))
    return Status::invalidArgument("square_m must be in (0, 10] metres");
  if (!(min_sharpness >= 0.0) || !std::isfinite(min_sharpness))
    return Status::invalidArgument("min_sharpness must be >= 0");
  if (!(min_motion_px >= 0.0) || !std::isfinite(min_motion_px))
    return Status::invalidArgument("min_motion_px must be >= 0");
  if (min_pairs < 3 || min_pairs > 1000)
    return Status::invalidArgument("min_pairs must be in [3, 1000]");
  if (!(min_coverage >= 0.0 && min_coverage <= 1.0))
    return Status::invalidArgument("min_coverage must be in [0, 1]");
  if (!(max_view_rms_px > 0.0)) return Status::invalidArgument("max_view_rms_px must be > 0");
  return Status::ok();
}

StereoCalibrator::StereoCalibrator(StereoCalibrationParams params)
    : params_(params), init_(params.validate()) {}

Status StereoCalibrator::addPair(const cv::Mat& left, const cv::Mat& right, const std::string& name,
                                 bool& accepted) {
  accepted = false;
  if (!init_) return init_;
  if (left.type() != CV_8UC1 || right.type() != CV_8UC1 || left.empty() || right.empty())
    return Status::invalidArgument(name + ": views must be non-empty 8-bit grey images");
  if (left.size() != right.size())
    return Status::invalidArgument("mixed image sizes: " + name + " left is " +
                                   sizeText(left.size()) + ", right is " + sizeText(right.size()));
  if (pairs_seen_ == 0) size_ = left.size();
  if (left.size() != size_)
    return Status::invalidArgument("mixed image sizes: " + name + " is " + sizeText(left.size()) +
                                   ", the first pair is " + sizeText(size_));
  ++pairs_seen_;
  View v{name, {}, {}};
  const bool found_l = detect(left, params_, v.left);
  const bool found_r = detect(right, params_, v.right);
  if (!found_l || !found_r) {
    rejected_.push_back(
        {name, std::string("board not found in ") + (!found_l && !found_r ? "left and right"
                                                     : !found_l           ? "left"
                                                                          : "right")});
    return Status::ok();
  }
  ++boards_found_;
  // The detector may number a board from either end; the right view must follow the left's
  // order (the cameras look the same way, so first->last corner directions must agree).
  const cv::Point2f dl = v.left.back() - v.left.front(), dr = v.right.back() - v.right.front();
  if (dl.dot(dr) < 0) std::reverse(v.right.begin(), v.right.end());
  const double s_l = sharpness(left, v.left), s_r = sharpness(right, v.right);
  if (s_l < params_.min_sharpness || s_r < params_.min_sharpness) {
    const bool l = s_l < params_.min_sharpness;
    char buf[96];
    std::snprintf(buf, sizeof buf, "blurred (%s sharpness %.1f < %.1f)", l ? "left" : "right",
                  l ? s_l : s_r, params_.min_sharpness);
    rejected_.push_back({name, buf});
    return Status::ok();
  }
  for (const View& a : views_)
    if (meanMotion(a.left, v.left) < params_.min_motion_px &&
        meanMotion(a.right, v.right) < params_.min_motion_px) {
      char buf[64];
      std::snprintf(buf, sizeof buf, " (corners moved < %.1f px)", params_.min_motion_px);
      rejected_.push_back({name, "duplicate of " + a.name + buf});
      return Status::ok();
    }
  views_.push_back(std::move(v));
  accepted = true;
  return Status::ok();
}

Result<StereoCalibrationResult> StereoCalibrator::calibrate() const {
  if (!init_) return init_;
  if (pairs_seen_ == 0) return Status::invalidArgument("no image pair given");
  const std::string board =
      std::to_string(params_.board_cols) + "x" + std::to_string(params_.board_rows);
  if (boards_found_ == 0)
    return Status::invalidArgument(
        "the " + board + " board (inner corners) was found in none of the " +
        std::to_string(pairs_seen_) +
        " pairs: wrong --board size (count inner corners, not squares) or no board in view");
  StereoCalibrationResult res;
  res.rejected = rejected_;
  std::vector<const View*> views;
  for (const View& v : views_) views.push_back(&v);
  auto too_few = [&](std::size_t n) {
    std::string why;
    for (std::size_t i = 0; i < res.rejected.size() && i < 5; ++i)
      why += (i ? "; " : "") + res.rejected[i].pair + ": " + res.rejected[i].reason;
    if (res.rejected.size() > 5) why += "; ...";
    return Status::invalidArgument("too few usable pairs: " + std::to_string(n) + " of " +
                                   std::to_string(pairs_seen_) + ", need " +
                                   std::to_string(params_.min_pairs) + " (rejected " +
                                   std::to_string(res.rejected.size()) + ": " + why + ")");
  };
  std::vector<cv::Point3f> board_pts;
  for (int r = 0; r < params_.board_rows; ++r)
    for (int c = 0; c < params_.board_cols; ++c)
      board_pts.emplace_back(static_cast<float>(c * params_.square_m),
                             static_cast<float>(r * params_.square_m), 0.0f);
  Solve s;
  std::vector<std::vector<cv::Point2f>> l, r;
  try {
    for (int round = 0; round < 2; ++round) {
      if (views.size() < static_cast<std::size_t>(params_.min_pairs)) return too_few(views.size());
      l.clear();
      r.clear();
      for (const View* v : views) {
        l.push_back(v->left);
        r.push_back(v->right);
      }
      const std::vector<std::vector<cv::Point3f>> obj(views.size(), board_pts);
      s = solve(obj, l, r, size_, params_.fix_intrinsic);
      if (round == 1) break;
      std::vector<const View*> kept;
      for (std::size_t i = 0; i < views.size(); ++i) {
        const double el = s.per_view.at<double>(static_cast<int>(i), 0);
        const double er = s.per_view.at<double>(static_cast<int>(i), 1);
        if (std::max(el, er) <= params_.max_view_rms_px) {
          kept.push_back(views[i]);
          continue;
        }
        char buf[96];
        std::snprintf(buf, sizeof buf, "reprojection outlier (RMS left %.2f, right %.2f > %.2f px)",
                      el, er, params_.max_view_rms_px);
        res.rejected.push_back({views[i]->name, buf});
      }
      if (kept.size() == views.size()) break;
      views.swap(kept);
    }
  } catch (const cv::Exception& e) {
    return Status::failedPrecondition(std::string("calibration failed in OpenCV: ") + e.what());
  }
  res.coverage_left = coverage(l, size_);
  res.coverage_right = coverage(r, size_);
  if (std::min(res.coverage_left, res.coverage_right) < params_.min_coverage) {
    char buf[200];
    std::snprintf(buf, sizeof buf,
                  "poor coverage: the board corners touch %.0f%% (left) and %.0f%% (right) of the "
                  "3x3 image cells, need %.0f%%: show the board near the image corners and edges",
                  100 * res.coverage_left, 100 * res.coverage_right, 100 * params_.min_coverage);
    return Status::failedPrecondition(buf);
  }
  for (const View* v : views) res.used.push_back(v->name);
  res.rms_left_px = s.rms_l;
  res.rms_right_px = s.rms_r;
  res.rms_pair_px = s.rms_pair;
  if (s.std_l.total() >= 4) {
    const double scx = s.std_l.at<double>(2), scy = s.std_l.at<double>(3);
    res.sigma_principal_point_left_px = std::sqrt(0.5 * (scx * scx + scy * scy));
    res.sigma_f_left_rel = s.std_l.at<double>(0) / s.K1.at<double>(0, 0);
  }
  res.file = {s.K1, s.D1.reshape(1, 1), s.K2,        s.D2.reshape(1, 1),
              s.R,  s.T.reshape(1, 3),  size_.width, size_.height};
  cv::stereoRectify(s.K1, s.D1, s.K2, s.D2, size_, s.R, s.T, res.R1, res.R2, res.P1, res.P2, res.Q,
                    cv::CALIB_ZERO_DISPARITY, 0.0);
  res.baseline_m = -res.P2.at<double>(0, 3) / res.P2.at<double>(0, 0);
  double sum = 0.0, mx = 0.0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < l.size(); ++i) {
    std::vector<cv::Point2f> ul, ur;
    cv::undistortPoints(l[i], ul, s.K1, s.D1, res.R1, res.P1);
    cv::undistortPoints(r[i], ur, s.K2, s.D2, res.R2, res.P2);
    for (std::size_t k = 0; k < ul.size(); ++k) {
      const double e = std::abs(static_cast<double>(ul[k].y - ur[k].y));
      sum += e;
      mx = std::max(mx, e);
      ++n;
    }
  }
  res.epipolar_mean_px = n ? sum / static_cast<double>(n) : 0.0;
  res.epipolar_max_px = mx;
  return res;
}

cv::Mat renderRectifiedCheck(const StereoCalibrationResult& r, const cv::Mat& left,
                             const cv::Mat& right, int line_step_px) {
  const cv::Size size(r.file.width, r.file.height);
  cv::Mat out(size.height, 2 * size.width, CV_8UC3);
  const cv::Mat* raw[2] = {&left, &right};
  const cv::Mat* K[2] = {&r.file.K1, &r.file.K2};
  const cv::Mat* D[2] = {&r.file.D1, &r.file.D2};
  const cv::Mat* R[2] = {&r.R1, &r.R2};
  const cv::Mat* P[2] = {&r.P1, &r.P2};
  for (int i = 0; i < 2; ++i) {
    cv::Mat mx, my, rect;
    cv::initUndistortRectifyMap(*K[i], *D[i], *R[i], *P[i], size, CV_16SC2, mx, my);
    cv::remap(*raw[i], rect, mx, my, cv::INTER_LINEAR);
    cv::cvtColor(rect, out(cv::Rect(i * size.width, 0, size.width, size.height)),
                 cv::COLOR_GRAY2BGR);
  }
  for (int y = line_step_px / 2; y < size.height; y += std::max(1, line_step_px))
    cv::line(out, {0, y}, {out.cols - 1, y}, cv::Scalar(0, 255, 0), 1);
  return out;
}

}  // namespace svslam::drivers
