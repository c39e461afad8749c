// The two renderers of a Scene: hand-written SVG and OpenCV drawing.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/imgproc.hpp>
#include <string>

#include "pipeline/tools/plot/plot_scene.hpp"

namespace svslam::plot {

namespace {

std::string hex(Rgb c) {
  char buf[8];
  std::snprintf(buf, sizeof buf, "#%02x%02x%02x", c.r, c.g, c.b);
  return buf;
}

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f", v);
  return buf;
}

std::string xmlEscape(const std::string& s) {
  std::string out;
  for (const char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        // Control characters are not allowed in XML 1.0.
        if (static_cast<unsigned char>(c) < 0x20 && c != '\t' && c != '\n') {
          out += ' ';
        } else {
          out += c;
        }
    }
  }
  return out;
}

struct SvgWriter {
  std::string out;
  void operator()(const PathItem& p) {
    if (p.px.empty()) return;
    out += "<path";
    if (!p.id.empty()) out += " id=\"" + xmlEscape(p.id) + "\"";
    if (!p.cls.empty()) out += " class=\"" + xmlEscape(p.cls) + "\"";
    out += " d=\"";
    for (std::size_t i = 0; i < p.px.size(); ++i)
      out += (i == 0 ? "M " : " L ") + num(p.px[i].x()) + " " + num(p.px[i].y());
    if (p.closed) out += " Z";
    out += "\" fill=\"none\" stroke=\"" + hex(p.stroke) + "\" stroke-width=\"" + num(p.width_px) +
           "\" stroke-linejoin=\"round\" stroke-linecap=\"round\"/>\n";
  }
  void operator()(const DotsItem& d) {
    out += "<g class=\"" + xmlEscape(d.cls) + "\" fill=\"" + hex(d.fill) + "\">\n";
    for (const auto& q : d.px)
      out += "<circle cx=\"" + num(q.x()) + "\" cy=\"" + num(q.y()) + "\" r=\"" + num(d.radius_px) +
             "\"/>\n";
    out += "</g>\n";
  }
  void operator()(const RectItem& r) {
    out += "<rect x=\"" + num(r.x) + "\" y=\"" + num(r.y) + "\" width=\"" + num(r.w) +
           "\" height=\"" + num(r.h) + "\" fill=\"" + (r.filled ? hex(r.fill) : "none") + "\"";
    if (r.outline) out += " stroke=\"#787878\" stroke-width=\"1\"";
    out += "/>\n";
  }
  void operator()(const TextItem& t) {
    const char* anchor = t.anchor == TextItem::Anchor::kStart    ? "start"
                         : t.anchor == TextItem::Anchor::kMiddle ? "middle"
                                                                 : "end";
    out += "<text x=\"" + num(t.px.x()) + "\" y=\"" + num(t.px.y()) + "\" font-size=\"" +
           num(t.size_px) + "\" text-anchor=\"" + anchor + "\" fill=\"" + hex(t.color) + "\"";
    if (t.vertical) out += " transform=\"rotate(-90 " + num(t.px.x()) + " " + num(t.px.y()) + ")\"";
    out += ">" + xmlEscape(t.text) + "</text>\n";
  }
};

cv::Scalar bgr(Rgb c) { return cv::Scalar(c.b, c.g, c.r); }

constexpr int kShift = 4;  // sub-pixel bits of OpenCV's drawing
cv::Point fixedPoint(const Eigen::Vector2d& p) {
  return {static_cast<int>(std::lround(p.x() * (1 << kShift))),
          static_cast<int>(std::lround(p.y() * (1 << kShift)))};
}

// OpenCV's Hershey simplex: cap height of about 22 px at scale 1; SVG font-size is the em, whose
// cap height is about 0.72 em. A slightly larger scale keeps the thin strokes legible.
double fontScale(double size_px) { return size_px / 26.0; }

struct PngWriter {
  cv::Mat& img;
  void operator()(const PathItem& p) {
    if (p.px.empty()) return;
    std::vector<cv::Point> pts;
    pts.reserve(p.px.size());
    for (const auto& q : p.px) pts.push_back(fixedPoint(q));
    const int thickness = std::max(1, static_cast<int>(std::lround(p.width_px)));
    if (pts.size() == 1) {
      cv::circle(img, pts[0], (thickness << kShift) / 2, bgr(p.stroke), cv::FILLED, cv::LINE_AA,
                 kShift);
      return;
    }
    cv::polylines(img, pts, p.closed, bgr(p.stroke), thickness, cv::LINE_AA, kShift);
  }
  void operator()(const DotsItem& d) {
    const int r = std::max(1, static_cast<int>(std::lround(d.radius_px * (1 << kShift))));
    for (const auto& q : d.px)
      cv::circle(img, fixedPoint(q), r, bgr(d.fill), cv::FILLED, cv::LINE_AA, kShift);
  }
  void operator()(const RectItem& r) {
    const cv::Rect rect(static_cast<int>(std::lround(r.x)), static_cast<int>(std::lround(r.y)),
                        std::max(1, static_cast<int>(std::lround(r.w))),
                        std::max(1, static_cast<int>(std::lround(r.h))));
    if (r.filled) cv::rectangle(img, rect, bgr(r.fill), cv::FILLED);
    if (r.outline) cv::rectangle(img, rect, cv::Scalar(120, 120, 120), 1);
  }
  void operator()(const TextItem& t) {
    if (t.text.empty()) return;
    const double scale = fontScale(t.size_px);
    int base = 0;
    const cv::Size sz = cv::getTextSize(t.text, cv::FONT_HERSHEY_SIMPLEX, scale, 1, &base);
    const double shift = t.anchor == TextItem::Anchor::kStart    ? 0.0
                         : t.anchor == TextItem::Anchor::kMiddle ? 0.5 * sz.width
                                                                 : sz.width;
    if (!t.vertical) {
      cv::putText(img, t.text,
                  cv::Point(static_cast<int>(std::lround(t.px.x() - shift)),
                            static_cast<int>(std::lround(t.px.y()))),
                  cv::FONT_HERSHEY_SIMPLEX, scale, bgr(t.color), 1, cv::LINE_AA);
      return;
    }
    // Drawn horizontally on white, turned, and laid over the image (darkest wins).
    cv::Mat tmp(sz.height + base + 4, sz.width + 4, CV_8UC3, cv::Scalar(255, 255, 255));
    cv::putText(tmp, t.text, cv::Point(2, sz.height + 2), cv::FONT_HERSHEY_SIMPLEX, scale,
                bgr(t.color), 1, cv::LINE_AA);
    cv::Mat rot;
    cv::rotate(tmp, rot, cv::ROTATE_90_COUNTERCLOCKWISE);
    // Row sz.height + 2 of tmp (the baseline) becomes column sz.height + 2 of rot.
    const int x0 = static_cast<int>(std::lround(t.px.x())) - (sz.height + 2);
    // Column c of tmp becomes row rot.rows - 1 - c: the anchor (column 2 + shift) goes to px.y.
    const int y0 = static_cast<int>(std::lround(t.px.y() - (rot.rows - 1 - (2 + shift))));
    const cv::Rect dst = cv::Rect(x0, y0, rot.cols, rot.rows) & cv::Rect(0, 0, img.cols, img.rows);
    if (dst.area() <= 0) return;
    const cv::Rect src(dst.x - x0, dst.y - y0, dst.width, dst.height);
    cv::Mat roi = img(dst);
    cv::min(roi, rot(src), roi);
  }
};

}  // namespace

std::string sceneToSvg(const Scene& s) {
  SvgWriter w;
  w.out =
      "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<svg xmlns=\"http://www.w3.org/2000/svg\" "
      "version=\"1.1\" width=\"" +
      std::to_string(s.width_px) + "\" height=\"" + std::to_string(s.height_px) +
      "\" viewBox=\"0 0 " + std::to_string(s.width_px) + " " + std::to_string(s.height_px) +
      "\" font-family=\"DejaVu Sans, Helvetica, Arial, sans-serif\">\n";
  for (const auto& item : s.items) std::visit(w, item);
  w.out += "</svg>\n";
  return w.out;
}

cv::Mat sceneToImage(const Scene& s) {
  cv::Mat img(std::max(s.height_px, 1), std::max(s.width_px, 1), CV_8UC3,
              cv::Scalar(255, 255, 255));
  PngWriter w{img};
  for (const auto& item : s.items) std::visit(w, item);
  return img;
}

}  // namespace svslam::plot
