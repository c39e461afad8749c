#include "pipeline/tools/plot/plot_figures.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace svslam::plot {

namespace {

const Rgb kEstimate{31, 119, 180};
const Rgb kGroundTruth{44, 160, 44};
const Rgb kEllipse{255, 127, 14};
const Rgb kStart{0, 0, 0};
const Rgb kActive{214, 39, 40};
const Rgb kRetired{165, 165, 165};
const Rgb kP50{31, 119, 180}, kP99{255, 127, 14}, kMax{214, 39, 40};

std::string fmt(const char* f, double a) {
  char buf[128];
  std::snprintf(buf, sizeof buf, f, a);
  return buf;
}

Eigen::Vector2d top(const HorizontalFrame& f, const Eigen::Vector3d& p) {
  return {f.u.dot(p), f.v.dot(p)};
}

std::string axisLabel(const std::string& name) { return name + " (m)"; }

Series line(std::string id, std::string label, Rgb c, double w) {
  Series s;
  s.kind = Series::Kind::kLine;
  s.id = std::move(id);
  s.label = std::move(label);
  s.color = c;
  s.width_px = w;
  return s;
}

Series startMarker(const Eigen::Vector2d& p) {
  Series s;
  s.kind = Series::Kind::kPoints;
  s.id = "start";
  s.label = "start";
  s.color = kStart;
  s.radius_px = 3.5;
  s.xy = {p};
  return s;
}

Figure base(const PlotSettings& s, std::string title) {
  Figure f;
  f.width_px = s.width_px;
  f.height_px = s.height_px;
  f.title = std::move(title);
  return f;
}

std::string viewNote(const HorizontalFrame& f) {
  return "top view: " + f.u_name + " right, " + f.v_name + " up the page (seen from " + f.up_name +
         "); run frame = first left camera, metres";
}

}  // namespace

Result<Figure> trajectoryTopFigure(const RunPlotData& d, const PlotSettings& s, int* ellipses) {
  Figure f = base(s, "Trajectory, top view: " + d.run_name);
  Panel p;
  p.equal_aspect = true;
  p.title = std::to_string(d.p_est.size()) + " poses";
  p.note = viewNote(s.frame);
  p.x_label = axisLabel(s.frame.u_name);
  p.y_label = axisLabel(s.frame.v_name);
  int drawn = 0;
  double largest_m = 0;
  if (!d.cov_p.empty()) {
    const int n = static_cast<int>(d.p_est.size());
    const int every = s.ellipse_every > 0 ? s.ellipse_every : std::max(1, n / 20);
    Eigen::Matrix<double, 3, 2> B;
    B << s.frame.u, s.frame.v;
    for (int i = 0; i < n && i < static_cast<int>(d.cov_p.size()); ++i) {
      if (i % every != 0 && i != n - 1) continue;
      Eigen::Matrix2d C = B.transpose() * d.cov_p[i] * B;
      C = 0.5 * (C + C.transpose());  // B^T P B is symmetric up to rounding
      auto e = covarianceEllipse(C, 2.0);
      if (!e)
        return Status::invalidArgument("position covariance of pose " + std::to_string(i) + ": " +
                                       e.status().message());
      if (!(e->a > 0)) continue;  // the first pose: exactly known
      largest_m = std::max(largest_m, e->a);
      Series el;
      el.kind = Series::Kind::kPolygon;
      el.id = "ellipse_" + std::to_string(i);
      el.color = kEllipse;
      el.width_px = 1;
      el.xy = ellipsePoints(top(s.frame, d.p_est[i]), *e, 48);
      if (drawn == 0)
        el.label = every == 1 ? "2-sigma position (every pose)"
                              : "2-sigma position (every " + std::to_string(every) + " poses)";
      p.series.push_back(std::move(el));
      ++drawn;
    }
    f.caption =
        "k = 2 ellipses of the horizontal position covariance (86.5 % in 2-D); largest "
        "semi-axis " +
        fmt("%.3g m", largest_m);
  } else {
    f.caption = "no pose_covariance.txt (vo mode): no uncertainty ellipses";
  }
  if (ellipses) *ellipses = drawn;
  if (!d.p_gt.empty()) {
    Series g = line("ground_truth", d.gt_label, kGroundTruth, 4);  // under the estimate
    for (const auto& q : d.p_gt) g.xy.push_back(top(s.frame, q));
    p.series.push_back(std::move(g));
  }
  Series e = line("trajectory", "estimate (trajectory_tum.txt)", kEstimate, 1.5);
  for (const auto& q : d.p_est) e.xy.push_back(top(s.frame, q));
  p.series.push_back(std::move(e));
  if (!d.p_est.empty()) p.series.push_back(startMarker(top(s.frame, d.p_est.front())));
  f.panels.push_back(std::move(p));
  return f;
}

Figure altitudeFigure(const RunPlotData& d, const PlotSettings& s) {
  Figure f = base(s, "Altitude against time: " + d.run_name);
  Panel p;
  p.title = "altitude = " + s.frame.up_name + " coordinate of the camera (up positive)";
  p.x_label = "time since the first frame (s)";
  p.y_label = "altitude (m)";
  const Eigen::Vector3d& up = s.frame.up;
  if (!d.cov_p.empty()) {
    Series hi = line("altitude_plus_2sigma", "estimate +/- 2 sigma", kEllipse, 1);
    Series lo = line("altitude_minus_2sigma", "", kEllipse, 1);
    for (std::size_t i = 0; i < d.p_est.size() && i < d.cov_p.size(); ++i) {
      const double sigma = std::sqrt(std::max(0.0, up.dot(d.cov_p[i] * up)));
      hi.xy.emplace_back(d.t_s[i], up.dot(d.p_est[i]) + 2 * sigma);
      lo.xy.emplace_back(d.t_s[i], up.dot(d.p_est[i]) - 2 * sigma);
    }
    p.series.push_back(std::move(hi));
    p.series.push_back(std::move(lo));
  }
  if (!d.p_gt.empty() && d.t_gt_s.size() == d.p_gt.size()) {
    Series g = line("altitude_ground_truth", d.gt_label, kGroundTruth, 4);
    for (std::size_t i = 0; i < d.p_gt.size(); ++i)
      g.xy.emplace_back(d.t_gt_s[i], up.dot(d.p_gt[i]));
    p.series.push_back(std::move(g));
  } else if (!d.p_gt.empty()) {
    p.note = "ground truth left out: its poses have no time stamps and do not pair by index";
  }
  Series e = line("altitude", "estimate", kEstimate, 1.5);
  for (std::size_t i = 0; i < d.p_est.size(); ++i) e.xy.emplace_back(d.t_s[i], up.dot(d.p_est[i]));
  p.series.push_back(std::move(e));
  f.panels.push_back(std::move(p));
  f.caption = "time from trajectory_tum.txt; altitude relative to the first camera position";
  return f;
}

Figure landmarksFigure(const RunPlotData& d, const PlotSettings& s) {
  Figure f = base(s, "Landmarks, top view: " + d.run_name);
  Panel p;
  p.equal_aspect = true;
  int active = 0;
  Series retired_pts, active_pts;
  retired_pts.kind = active_pts.kind = Series::Kind::kPoints;
  retired_pts.id = "landmarks_retired";
  active_pts.id = "landmarks_active";
  retired_pts.color = kRetired;
  active_pts.color = kActive;
  retired_pts.radius_px = 1.5;
  active_pts.radius_px = 2;
  for (const auto& l : d.landmarks) {
    (l.active ? active_pts : retired_pts).xy.push_back(top(s.frame, l.p_world));
    active += l.active ? 1 : 0;
  }
  const int retired = static_cast<int>(d.landmarks.size()) - active;
  retired_pts.label = "retired (" + std::to_string(retired) + ")";
  active_pts.label = "in the filter at the end (" + std::to_string(active) + ")";
  p.title = std::to_string(d.landmarks.size()) + " landmarks (landmarks.ply)";
  p.note = viewNote(s.frame);
  p.x_label = axisLabel(s.frame.u_name);
  p.y_label = axisLabel(s.frame.v_name);
  p.series.push_back(std::move(retired_pts));
  p.series.push_back(std::move(active_pts));
  Series e = line("trajectory", "camera trajectory", kEstimate, 1.5);
  for (const auto& q : d.p_est) e.xy.push_back(top(s.frame, q));
  p.series.push_back(std::move(e));
  f.panels.push_back(std::move(p));
  return f;
}

Figure latencyFigure(const RunPlotData& d, const PlotSettings& s) {
  Figure f = base(s, "Processing time per stage: " + d.run_name);
  Panel p;
  std::int64_t frames = 0;
  const double h = 0.26;
  for (std::size_t k = 0; k < d.stages.size(); ++k) {
    const auto& st = d.stages[k];
    const double y = -static_cast<double>(k);
    frames = std::max(frames, st.count);
    p.y_categories.emplace_back(y, st.stage);
    const double vals[3] = {st.p50_ms, st.p99_ms, st.max_ms};
    const Rgb cols[3] = {kP50, kP99, kMax};
    for (int j = 0; j < 3; ++j)
      if (std::isfinite(vals[j]))
        p.bars.push_back(
            {y + h * (1 - j) - h / 2 + 0.02, y + h * (1 - j) + h / 2 - 0.02, vals[j], cols[j]});
  }
  p.legend_swatches = {{"p50", kP50}, {"p99", kP99}, {"max", kMax}};
  p.title = "stats.json stage_ms: p50 / p99 / max per stage (up to " + std::to_string(frames) +
            " samples each)";
  p.x_label = "ms";
  f.panels.push_back(std::move(p));
  if (d.has_latency_log && !d.latency_ms.empty()) {
    Panel q;
    const auto [mn, mx] = std::minmax_element(d.latency_ms.begin(), d.latency_ms.end());
    const Ticks t = niceTicks(*mn, *mx + 1e-9, 30);
    const double bin = t.step > 0 ? t.step : 1.0;
    const double lo = std::floor(*mn / bin) * bin;
    const int nb = static_cast<int>(std::clamp(std::ceil((*mx - lo) / bin + 1e-9), 1.0, 1000.0));
    std::vector<int> counts(static_cast<std::size_t>(nb), 0);
    for (double v : d.latency_ms)
      ++counts[static_cast<std::size_t>(std::clamp((v - lo) / bin, 0.0, nb - 1.0))];
    Series hist = line("latency_histogram", "", kEstimate, 1.5);
    hist.xy.emplace_back(lo, 0);
    for (int b = 0; b < nb; ++b) {
      hist.xy.emplace_back(lo + b * bin, counts[b]);
      hist.xy.emplace_back(lo + (b + 1) * bin, counts[b]);
    }
    hist.xy.emplace_back(lo + nb * bin, 0);
    q.series.push_back(std::move(hist));
    q.title = "latency.txt: capture -> pose published, " + std::to_string(d.latency_ms.size()) +
              " frames (histogram, bins of " + fmt("%g", bin) + " ms)";
    q.x_label = "ms";
    q.y_label = "frames";
    f.panels.push_back(std::move(q));
  }
  f.caption = d.has_latency_log
                  ? "stats.json keeps quantiles, not samples: bars, not histograms, per stage"
                  : "stats.json keeps quantiles, not samples: bars, not histograms (per-frame "
                    "latency: pipeline.latency_log)";
  return f;
}

}  // namespace svslam::plot
