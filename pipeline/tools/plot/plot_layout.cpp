// layoutFigure: panels stacked top to bottom, each with its axes, ticks, grid, data and legend.
#include <algorithm>
#include <cmath>
#include <limits>

#include "eval/plot_scales.hpp"
#include "pipeline/tools/plot/plot_scene.hpp"

namespace svslam::plot {

namespace {

const Rgb kBlack{0, 0, 0};
const Rgb kGrid{225, 225, 225};
const Rgb kFrame{120, 120, 120};
const Rgb kWhite{255, 255, 255};
const Rgb kNoteColor{90, 90, 90};
constexpr double kTickSize = 11, kLabelSize = 12.5, kTitleSize = 14, kFigureTitleSize = 17;

struct Range {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  void add(double v) {
    if (!std::isfinite(v)) return;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  bool empty() const { return !(lo <= hi); }
  double span() const { return hi - lo; }
  // Non-empty, non-degenerate, with a relative margin on both sides (on the side away from 0
  // only when `keep_zero` and the range starts or ends at 0).
  void finish(double margin, bool keep_zero) {
    if (empty()) lo = 0, hi = 1;
    if (span() <= 0) {
      const double d = std::max(std::abs(lo) * 0.1, 0.5);
      lo -= d, hi += d;
    }
    const double m = span() * margin;
    if (!(keep_zero && lo == 0)) lo -= m;
    if (!(keep_zero && hi == 0)) hi += m;
  }
};

TextItem text(double x, double y, std::string s, double size, TextItem::Anchor a,
              Rgb color = kBlack, bool vertical = false) {
  TextItem t;
  t.px = {x, y};
  t.text = std::move(s);
  t.size_px = size;
  t.anchor = a;
  t.color = color;
  t.vertical = vertical;
  return t;
}

PathItem line(double x0, double y0, double x1, double y1, Rgb c, double w, const char* cls) {
  PathItem p;
  p.cls = cls;
  p.px = {{x0, y0}, {x1, y1}};
  p.stroke = c;
  p.width_px = w;
  return p;
}

// `size` or less, so that `text` fits in `room` pixels.
double fitted(const std::string& text, double size, double room) {
  const double w = textWidthPx(text, size);
  return w > room ? size * room / w : size;
}

struct LegendEntry {
  std::string label;
  Rgb color;
  enum class Mark { kLine, kDot, kSwatch } mark;
  double width_px;
};

void layoutPanel(const Panel& p, double top, double height, int width, Scene& s) {
  using A = TextItem::Anchor;
  // Data ranges.
  Range xr, yr;
  for (const auto& se : p.series)
    for (const auto& v : se.xy) xr.add(v.x()), yr.add(v.y());
  for (const auto& b : p.bars) xr.add(0), xr.add(b.value), yr.add(b.lo), yr.add(b.hi);
  xr.finish(0.05, !p.bars.empty());
  yr.finish(p.y_categories.empty() ? 0.05 : 0.02, false);

  // Plot area.
  const double title_h = p.note.empty() ? 24 : 38;
  const double plot_top = top + title_h;
  const double plot_bottom = top + height - 40;
  Ticks yt = niceTicks(yr.lo, yr.hi, std::max(3, static_cast<int>((plot_bottom - plot_top) / 55)));
  double label_w = 0;
  if (p.y_categories.empty()) {
    for (double v : yt.values)
      label_w = std::max(label_w, textWidthPx(tickLabel(v, yt.decimals), kTickSize));
  } else {
    for (const auto& c : p.y_categories)
      label_w = std::max(label_w, textWidthPx(c.second, kTickSize));
  }
  const double plot_left = 12 + (p.y_label.empty() ? 0 : kLabelSize + 6) + label_w + 6;
  const double plot_right = width - 18.0;
  double w = plot_right - plot_left, h = plot_bottom - plot_top;
  if (w < 10 || h < 10) return;
  // Room above the data for the legend (a bar chart's legend finds a free corner instead).
  std::size_t legend_n = p.legend_swatches.size();
  for (const auto& se : p.series) legend_n += se.label.empty() ? 0 : 1;
  if (legend_n > 0 && p.y_categories.empty()) {
    const double frac = std::min(0.5, (8 + 17.0 * legend_n + 14) / h);
    yr.hi += yr.span() * frac / (1 - frac);
  }

  if (p.equal_aspect) {  // widen the range with more room per metre
    const double sx = w / xr.span(), sy = h / yr.span();
    if (sx > sy) {
      const double c = 0.5 * (xr.lo + xr.hi), half = 0.5 * w / sy;
      xr.lo = c - half, xr.hi = c + half;
    } else {
      const double c = 0.5 * (yr.lo + yr.hi), half = 0.5 * h / sx;
      yr.lo = c - half, yr.hi = c + half;
    }
  }
  const Ticks xt = niceTicks(xr.lo, xr.hi, std::max(3, static_cast<int>(w / 90)));
  yt = niceTicks(yr.lo, yr.hi, std::max(3, static_cast<int>(h / 55)));
  auto X = [&](double x) { return plot_left + (x - xr.lo) / xr.span() * w; };
  auto Y = [&](double y) { return plot_top + (yr.hi - y) / yr.span() * h; };

  // Titles, grid, ticks, axis labels.
  const double cx = 0.5 * (plot_left + plot_right);
  s.items.push_back(
      text(cx, top + 17, p.title, fitted(p.title, kTitleSize, width - 8.0), A::kMiddle));
  if (!p.note.empty())
    s.items.push_back(
        text(cx, top + 32, p.note, fitted(p.note, kTickSize, width - 8.0), A::kMiddle, kNoteColor));
  for (double v : xt.values) {
    s.items.push_back(line(X(v), plot_top, X(v), plot_bottom, kGrid, 1, "grid"));
    s.items.push_back(line(X(v), plot_bottom, X(v), plot_bottom + 4, kFrame, 1, "tick"));
    s.items.push_back(
        text(X(v), plot_bottom + 17, tickLabel(v, xt.decimals), kTickSize, A::kMiddle));
  }
  if (p.y_categories.empty()) {
    for (double v : yt.values) {
      s.items.push_back(line(plot_left, Y(v), plot_right, Y(v), kGrid, 1, "grid"));
      s.items.push_back(line(plot_left - 4, Y(v), plot_left, Y(v), kFrame, 1, "tick"));
      s.items.push_back(
          text(plot_left - 6, Y(v) + 4, tickLabel(v, yt.decimals), kTickSize, A::kEnd));
    }
  } else {
    for (const auto& [v, name] : p.y_categories)
      s.items.push_back(text(plot_left - 6, Y(v) + 4, name, kTickSize, A::kEnd));
  }
  s.items.push_back(text(cx, plot_bottom + 35, p.x_label, kLabelSize, A::kMiddle));
  if (!p.y_label.empty())
    s.items.push_back(text(12 + kLabelSize - 2, 0.5 * (plot_top + plot_bottom), p.y_label,
                           kLabelSize, A::kMiddle, kBlack, true));

  // Data: bars, then series in order.
  std::vector<Eigen::Vector2d> all_px;
  std::vector<RectItem> bar_rects;
  for (const auto& b : p.bars) {
    RectItem r;
    const double x0 = X(std::min(0.0, b.value)), x1 = X(std::max(0.0, b.value));
    r.x = x0, r.w = std::max(x1 - x0, 1.0);
    r.y = Y(b.hi), r.h = std::max(Y(b.lo) - Y(b.hi), 1.0);
    r.fill = b.color;
    s.items.push_back(r);
    bar_rects.push_back(r);
    all_px.emplace_back(x1, 0.5 * (Y(b.lo) + Y(b.hi)));
  }
  std::vector<LegendEntry> legend;
  for (const auto& se : p.series) {
    std::vector<Eigen::Vector2d> px;
    px.reserve(se.xy.size());
    for (const auto& v : se.xy) px.emplace_back(X(v.x()), Y(v.y()));
    all_px.insert(all_px.end(), px.begin(), px.end());
    if (se.kind == Series::Kind::kPoints) {
      DotsItem d;
      d.cls = se.id;
      d.px = std::move(px);
      d.radius_px = se.radius_px;
      d.fill = se.color;
      s.items.push_back(std::move(d));
    } else {
      PathItem pi;
      pi.id = se.id;
      pi.cls = se.kind == Series::Kind::kPolygon ? "ellipse" : "series";
      pi.px = std::move(px);
      pi.closed = se.kind == Series::Kind::kPolygon;
      pi.stroke = se.color;
      pi.width_px = se.width_px;
      s.items.push_back(std::move(pi));
    }
    if (!se.label.empty())
      legend.push_back(
          {se.label, se.color,
           se.kind == Series::Kind::kPoints ? LegendEntry::Mark::kDot : LegendEntry::Mark::kLine,
           se.width_px});
  }
  for (const auto& [label, color] : p.legend_swatches)
    legend.push_back({label, color, LegendEntry::Mark::kSwatch, 1});
  RectItem frame;
  frame.x = plot_left, frame.y = plot_top, frame.w = w, frame.h = h;
  frame.filled = false, frame.outline = true;
  s.items.push_back(frame);

  // Legend in the corner of the plot area that hides the fewest data points.
  if (legend.empty()) return;
  double lw = 0;
  for (const auto& e : legend) lw = std::max(lw, textWidthPx(e.label, kTickSize));
  const double bw = lw + 40, bh = 8 + 17.0 * legend.size();
  const Eigen::Vector2d corners[4] = {{plot_right - 8 - bw, plot_top + 8},
                                      {plot_left + 8, plot_top + 8},
                                      {plot_right - 8 - bw, plot_bottom - 8 - bh},
                                      {plot_left + 8, plot_bottom - 8 - bh}};
  std::size_t best = 0, best_hidden = std::numeric_limits<std::size_t>::max();
  for (std::size_t c = 0; c < 4; ++c) {
    std::size_t hidden = 0;
    for (const auto& q : all_px)
      hidden += q.x() >= corners[c].x() && q.x() <= corners[c].x() + bw &&
                q.y() >= corners[c].y() && q.y() <= corners[c].y() + bh;
    for (const auto& r : bar_rects)  // a bar under the box hides it, counted as many points
      hidden += 100 * (r.x < corners[c].x() + bw && r.x + r.w > corners[c].x() &&
                       r.y < corners[c].y() + bh && r.y + r.h > corners[c].y());
    if (hidden < best_hidden) best = c, best_hidden = hidden;
  }
  RectItem box;
  box.x = corners[best].x(), box.y = corners[best].y(), box.w = bw, box.h = bh;
  box.fill = kWhite, box.outline = true;
  s.items.push_back(box);
  for (std::size_t i = 0; i < legend.size(); ++i) {
    const auto& e = legend[i];
    const double y = box.y + 4 + 17.0 * i + 8.5;
    const double x = box.x + 8;
    if (e.mark == LegendEntry::Mark::kLine) {
      s.items.push_back(line(x, y, x + 22, y, e.color, std::max(e.width_px, 1.5), "legend"));
    } else if (e.mark == LegendEntry::Mark::kDot) {
      DotsItem d;
      d.cls = "legend";
      d.px = {{x + 11, y}};
      d.radius_px = 3;
      d.fill = e.color;
      s.items.push_back(d);
    } else {
      RectItem r;
      r.x = x + 3, r.y = y - 5, r.w = 16, r.h = 10, r.fill = e.color;
      s.items.push_back(r);
    }
    s.items.push_back(text(x + 28, y + 4, e.label, kTickSize, A::kStart));
  }
}

}  // namespace

double textWidthPx(const std::string& text, double size_px) {
  return 0.7 * size_px * static_cast<double>(text.size());
}

Scene layoutFigure(const Figure& f) {
  Scene s;
  s.width_px = f.width_px;
  s.height_px = f.height_px;
  RectItem bg;
  bg.w = f.width_px, bg.h = f.height_px, bg.fill = kWhite;
  s.items.push_back(bg);
  s.items.push_back(text(0.5 * f.width_px, 24, f.title,
                         fitted(f.title, kFigureTitleSize, f.width_px - 8.0),
                         TextItem::Anchor::kMiddle));
  const double top = 32;
  const double bottom = f.height_px - (f.caption.empty() ? 4.0 : 22.0);
  if (!f.caption.empty())
    s.items.push_back(text(0.5 * f.width_px, f.height_px - 8.0, f.caption,
                           fitted(f.caption, kTickSize, f.width_px - 8.0),
                           TextItem::Anchor::kMiddle, kNoteColor));
  if (f.panels.empty()) return s;
  const double ph = (bottom - top) / static_cast<double>(f.panels.size());
  for (std::size_t i = 0; i < f.panels.size(); ++i)
    layoutPanel(f.panels[i], top + ph * static_cast<double>(i), ph, f.width_px, s);
  return s;
}

}  // namespace svslam::plot
