#include "drivers/files/trajectory_io.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "drivers/files/yaml_lists.hpp"

namespace svslam::drivers {
namespace {

std::string where(const std::string& path, int line) { return path + ":" + std::to_string(line); }

// A time written as [-]SECONDS[.FRACTION] with at most 9 fraction digits, read exactly into
// nanoseconds (a double holds about 16 digits: 1.4e9 s to the nanosecond needs 19). False for any
// other form (exponent, more digits, out of int64 range): the caller uses the double value.
bool exactSecondsToNs(const std::string& tok, std::int64_t& t_ns) {
  std::size_t i = 0;
  const bool negative = !tok.empty() && tok[0] == '-';
  if (negative || (!tok.empty() && tok[0] == '+')) i = 1;
  std::int64_t whole = 0;
  std::size_t digits = 0;
  for (; i < tok.size() && tok[i] >= '0' && tok[i] <= '9'; ++i, ++digits) {
    if (whole > (INT64_MAX / 1000000000 - 9) / 10) return false;  // whole s * 1e9 must fit
    whole = whole * 10 + (tok[i] - '0');
  }
  std::int64_t frac = 0;
  int frac_digits = 0;
  if (i < tok.size() && tok[i] == '.') {
    for (++i; i < tok.size() && tok[i] >= '0' && tok[i] <= '9'; ++i, ++frac_digits) {
      if (frac_digits == 9) return false;
      frac = frac * 10 + (tok[i] - '0');
    }
  }
  if (i != tok.size() || digits + static_cast<std::size_t>(frac_digits) == 0) return false;
  for (int k = frac_digits; k < 9; ++k) frac *= 10;
  t_ns = whole * 1000000000 + frac;
  if (negative) t_ns = -t_ns;
  return true;
}

}  // namespace

Result<TrajectoryFile> readTrajectory(const std::string& path) {
  if (!std::filesystem::exists(path))
    return Status::notFound("trajectory file does not exist: " + path);
  std::ifstream f(path);
  if (!f) return Status::ioError("cannot open trajectory file " + path);
  std::ostringstream text;
  text << f.rdbuf();
  if (f.bad()) return Status::ioError("cannot read trajectory file " + path);
  return parseTrajectory(text.str(), path);
}

Result<TrajectoryFile> parseTrajectory(const std::string& text, const std::string& path) {
  std::istringstream f(text);
  TrajectoryFile out;
  std::string line;
  int line_no = 0;
  int expected = 0;
  while (std::getline(f, line)) {
    ++line_no;
    if (auto h = line.find('#'); h != std::string::npos) line = line.substr(0, h);
    for (char& c : line)
      if (c == ',') c = ' ';
    std::istringstream s(line);
    std::vector<double> v;
    std::string tok, first_tok;
    while (s >> tok) {
      if (v.empty()) first_tok = tok;
      char* end = nullptr;
      const double d = std::strtod(tok.c_str(), &end);
      if (end == tok.c_str() || *end != '\0')
        return Status::corruptData(where(path, line_no) + ": '" + tok + "' is not a number");
      v.push_back(d);
    }
    if (v.empty()) continue;
    if (expected == 0) {
      if (v.size() != 12 && v.size() != 8)
        return Status::corruptData(where(path, line_no) +
                                   ": expected 12 values (KITTI) or 8 (TUM), got " +
                                   std::to_string(v.size()));
      expected = static_cast<int>(v.size());
      out.format = expected == 12 ? TrajectoryFormat::kKitti : TrajectoryFormat::kTum;
    }
    if (static_cast<int>(v.size()) != expected)
      return Status::corruptData(where(path, line_no) + ": expected " + std::to_string(expected) +
                                 " values, got " + std::to_string(v.size()));
    for (double d : v)
      if (!std::isfinite(d)) return Status::corruptData(where(path, line_no) + ": NaN or infinity");
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    if (expected == 12) {
      Eigen::Matrix3d R;
      R << v[0], v[1], v[2], v[4], v[5], v[6], v[8], v[9], v[10];
      // Files store 7 significant digits: a rotation within kRotationTolerance is projected
      // onto the nearest one (unit quaternion); anything else is not a pose.
      const double off = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
      if (off > kRotationTolerance || R.determinant() < 0.0) {
        char buf[160];
        std::snprintf(buf, sizeof buf,
                      ": the 3x3 part is not a rotation (max |R^T R - I| = %.3g, det = %.3g; "
                      "allowed %g)",
                      off, R.determinant(), kRotationTolerance);
        return Status::corruptData(where(path, line_no) + buf);
      }
      T.linear() = Eigen::Quaterniond(R).normalized().toRotationMatrix();
      T.translation() = Eigen::Vector3d(v[3], v[7], v[11]);
    } else {
      Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);  // w, x, y, z
      if (std::abs(q.norm() - 1.0) > kRotationTolerance) {
        char buf[96];
        std::snprintf(buf, sizeof buf, ": the quaternion is not a unit one (norm %.6g)", q.norm());
        return Status::corruptData(where(path, line_no) + buf);
      }
      T.linear() = q.normalized().toRotationMatrix();
      T.translation() = Eigen::Vector3d(v[1], v[2], v[3]);
      if (!(std::abs(v[0]) < (v[0] > 1e12 ? 9.2e18 : 9.2e9)))  // int64 ns: +-9.22e18
        return Status::corruptData(where(path, line_no) + ": time stamp " + std::to_string(v[0]) +
                                   " is out of range (|t| < 9.2e9 s, or < 9.2e18 ns)");
      std::int64_t exact_ns = 0;
      if (v[0] <= 1e12 && exactSecondsToNs(first_tok, exact_ns))
        out.t_ns.push_back(exact_ns);  // seconds with up to 9 decimals: to the nanosecond
      else
        out.t_ns.push_back(v[0] > 1e12 ? static_cast<TimeNs>(std::llround(v[0]))
                                       : secondsToNs(v[0]));
    }
    out.poses.push_back(T);
  }
  if (out.poses.empty()) return Status::corruptData("no pose in trajectory file " + path);
  return out;
}

Result<Eigen::Isometry3d> readEurocTbs(const std::string& sensor_yaml) {
  auto text = readTextFile(sensor_yaml);
  if (!text) return text.status();
  return parseEurocTbs(*text, sensor_yaml);
}

Result<Eigen::Isometry3d> parseEurocTbs(const std::string& text, const std::string& sensor_yaml) {
  auto v = yamlNumberList(text, "T_BS", "data", sensor_yaml);
  if (!v) return v.status();
  if (v->size() != 16) return Status::corruptData(sensor_yaml + ": T_BS data must have 16 numbers");
  Eigen::Matrix4d M;
  for (int i = 0; i < 16; ++i) M(i / 4, i % 4) = (*v)[static_cast<std::size_t>(i)];
  Eigen::Isometry3d T;
  T.matrix() = M;
  return T;
}

Status associateTrajectories(const TrajectoryFile& gt, const TrajectoryFile& est, double max_dt_s,
                             std::vector<Eigen::Isometry3d>& gt_out,
                             std::vector<Eigen::Isometry3d>& est_out,
                             std::vector<std::size_t>* est_index) {
  gt_out.clear();
  est_out.clear();
  if (est_index) est_index->clear();
  if (gt.t_ns.empty() || est.t_ns.empty()) {
    if (gt.poses.size() != est.poses.size())
      return Status::invalidArgument(
          "trajectories without timestamps are paired by index, but they have " +
          std::to_string(gt.poses.size()) + " and " + std::to_string(est.poses.size()) + " poses");
    gt_out = gt.poses;
    est_out = est.poses;
    if (est_index)
      for (std::size_t i = 0; i < est.poses.size(); ++i) est_index->push_back(i);
    return Status::ok();
  }
  if (!std::is_sorted(gt.t_ns.begin(), gt.t_ns.end()))
    return Status::invalidArgument("ground-truth timestamps are not in increasing order");
  const TimeNs max_dt = secondsToNs(max_dt_s);
  for (std::size_t i = 0; i < est.t_ns.size(); ++i) {
    const auto it = std::lower_bound(gt.t_ns.begin(), gt.t_ns.end(), est.t_ns[i]);
    std::size_t best = gt.t_ns.size();
    TimeNs best_dt = max_dt + 1;
    for (auto c : {it, it == gt.t_ns.begin() ? it : it - 1}) {
      if (c == gt.t_ns.end()) continue;
      const TimeNs dt = std::llabs(*c - est.t_ns[i]);
      if (dt < best_dt) {
        best_dt = dt;
        best = static_cast<std::size_t>(c - gt.t_ns.begin());
      }
    }
    if (best == gt.t_ns.size()) continue;  // no ground truth close enough
    gt_out.push_back(gt.poses[best]);
    est_out.push_back(est.poses[i]);
    if (est_index) est_index->push_back(i);
  }
  if (gt_out.size() < 3)
    return Status::invalidArgument("fewer than 3 estimate stamps have ground truth within " +
                                   std::to_string(max_dt_s) + " s");
  return Status::ok();
}

}  // namespace svslam::drivers
