#include "eval/disparity_metrics.hpp"

#include <array>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <utility>

namespace svslam {
namespace {

std::string sizeString(int w, int h) { return std::to_string(w) + "x" + std::to_string(h); }

void appendFixed4(std::string& out, double v) {
  if (!std::isfinite(v)) {
    out += "null";
    return;
  }
  std::array<char, 64> buf{};
  const auto res =
      std::to_chars(buf.data(), buf.data() + buf.size(), v, std::chars_format::fixed, 4);
  if (res.ec != std::errc()) {
    out += "null";  // |v| too large for the buffer; cannot happen for percentages and pixels
    return;
  }
  out.append(buf.data(), res.ptr);
}

}  // namespace

Result<DisparityMetrics> evaluateDisparity(ImageView<const float> est, ImageView<const float> gt,
                                           ImageView<const std::uint8_t> mask) {
  if (est.empty() || gt.empty()) {
    return Status::invalidArgument("evaluateDisparity: empty image (estimate " +
                                   sizeString(est.width, est.height) + ", ground truth " +
                                   sizeString(gt.width, gt.height) + ")");
  }
  if (est.width != gt.width || est.height != gt.height) {
    return Status::invalidArgument("evaluateDisparity: estimate is " +
                                   sizeString(est.width, est.height) + " but ground truth is " +
                                   sizeString(gt.width, gt.height));
  }
  const bool use_mask = !mask.empty();
  if (use_mask && (mask.width != gt.width || mask.height != gt.height)) {
    return Status::invalidArgument("evaluateDisparity: mask is " +
                                   sizeString(mask.width, mask.height) + " but ground truth is " +
                                   sizeString(gt.width, gt.height));
  }

  constexpr std::array<double, 4> kThresholdsPx = {0.5, 1.0, 2.0, 3.0};
  std::array<std::int64_t, 4> bad{};
  std::int64_t evaluated = 0;
  std::int64_t valid = 0;
  double sum_abs = 0.0;
  double sum_sq = 0.0;
  for (int y = 0; y < gt.height; ++y) {
    const float* e_row = est.row(y);
    const float* g_row = gt.row(y);
    const std::uint8_t* m_row = use_mask ? mask.row(y) : nullptr;
    for (int x = 0; x < gt.width; ++x) {
      const float g = g_row[x];
      if (!std::isfinite(g) || !(g > 0.0f)) continue;
      if (m_row != nullptr && m_row[x] == 0) continue;
      ++evaluated;
      const float e = e_row[x];
      if (!std::isfinite(e)) continue;
      ++valid;
      const double err = std::abs(static_cast<double>(e) - static_cast<double>(g));
      sum_abs += err;
      sum_sq += err * err;
      for (std::size_t i = 0; i < kThresholdsPx.size(); ++i) {
        if (err > kThresholdsPx[i]) ++bad[i];
      }
    }
  }
  if (evaluated == 0) {
    return Status::invalidArgument(
        "evaluateDisparity: no evaluated pixel (ground truth never finite and > 0 inside the "
        "mask)");
  }

  DisparityMetrics m;
  m.evaluated = evaluated;
  m.valid = valid;
  const double e_count = static_cast<double>(evaluated);
  const double v_count = static_cast<double>(valid);
  const std::int64_t invalid = evaluated - valid;
  m.density_pct = 100.0 * v_count / e_count;
  std::array<double, 4> bad_valid{};
  std::array<double, 4> bad_all{};
  for (std::size_t i = 0; i < bad.size(); ++i) {
    bad_valid[i] = valid > 0 ? 100.0 * static_cast<double>(bad[i]) / v_count : 0.0;
    bad_all[i] = 100.0 * static_cast<double>(invalid + bad[i]) / e_count;
  }
  m.bad05_valid_pct = bad_valid[0];
  m.bad1_valid_pct = bad_valid[1];
  m.bad2_valid_pct = bad_valid[2];
  m.bad3_valid_pct = bad_valid[3];
  m.bad05_all_pct = bad_all[0];
  m.bad1_all_pct = bad_all[1];
  m.bad2_all_pct = bad_all[2];
  m.bad3_all_pct = bad_all[3];
  if (valid > 0) {
    m.mae_valid_px = sum_abs / v_count;
    m.rmse_valid_px = std::sqrt(sum_sq / v_count);
  }
  return m;
}

std::string toJson(const DisparityMetrics& m) {
  std::string out = "{";
  out += "\"evaluated\": " + std::to_string(m.evaluated);
  out += ", \"valid\": " + std::to_string(m.valid);
  const std::array<std::pair<const char*, double>, 11> fields = {{
      {"density_pct", m.density_pct},
      {"bad05_valid_pct", m.bad05_valid_pct},
      {"bad1_valid_pct", m.bad1_valid_pct},
      {"bad2_valid_pct", m.bad2_valid_pct},
      {"bad3_valid_pct", m.bad3_valid_pct},
      {"bad05_all_pct", m.bad05_all_pct},
      {"bad1_all_pct", m.bad1_all_pct},
      {"bad2_all_pct", m.bad2_all_pct},
      {"bad3_all_pct", m.bad3_all_pct},
      {"mae_valid_px", m.mae_valid_px},
      {"rmse_valid_px", m.rmse_valid_px},
  }};
  for (const auto& [name, value] : fields) {
    out += ", \"";
    out += name;
    out += "\": ";
    appendFixed4(out, value);
  }
  out += "}";
  return out;
}

}  // namespace svslam
