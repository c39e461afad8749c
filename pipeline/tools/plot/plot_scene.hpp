#pragma once
// The plots of `svslam plot`, in two steps so that the PNG and the SVG show the same thing:
//   Figure (data coordinates: panels, series, bars, axis labels)
//     -> layoutFigure -> Scene (pixel coordinates: paths, dots, rectangles, text; y down)
//     -> sceneToSvg (hand-written SVG text) / sceneToImage (OpenCV drawing, 8-bit BGR).
// Every series keeps one vertex per data point: a trajectory of n poses is one SVG <path> with
// n vertices ("M x y L x y ..."), its id the series id.
#include <Eigen/Core>
#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <utility>
#include <variant>
#include <vector>

namespace svslam::plot {

struct Rgb {
  std::uint8_t r = 0, g = 0, b = 0;
};

// One data series of a panel.
struct Series {
  enum class Kind { kLine, kPoints, kPolygon };  // polygon: closed outline (ellipses)
  Kind kind = Kind::kLine;
  std::string id;     // SVG id (unique) or empty
  std::string label;  // legend entry; empty: not in the legend
  Rgb color;
  double width_px = 1.5;   // line width (lines, polygons)
  double radius_px = 2.0;  // dot radius (points)
  std::vector<Eigen::Vector2d> xy;
};

// A bar from 0 to `value` along x (horizontal bar chart), across [lo, hi] on y.
struct Bar {
  double lo = 0, hi = 0, value = 0;
  Rgb color;
};

struct Panel {
  std::string title, x_label, y_label;
  bool equal_aspect = false;  // same metres per pixel on both axes (top views)
  std::vector<Series> series;
  std::vector<Bar> bars;
  std::vector<std::pair<double, std::string>> y_categories;  // replace the numeric y ticks
  std::vector<std::pair<std::string, Rgb>> legend_swatches;  // legend entries of bars
  std::string note;  // one line under the panel title (e.g. why something is missing)
};

struct Figure {
  int width_px = 800, height_px = 600;
  std::string title, caption;  // caption: one line at the bottom
  std::vector<Panel> panels;   // stacked top to bottom
};

// Pixel-space drawing items, in drawing order.
struct PathItem {
  std::string id, cls;
  std::vector<Eigen::Vector2d> px;
  bool closed = false;
  Rgb stroke;
  double width_px = 1;
};
struct DotsItem {
  std::string cls;
  std::vector<Eigen::Vector2d> px;
  double radius_px = 2;
  Rgb fill;
};
struct RectItem {
  double x = 0, y = 0, w = 0, h = 0;
  Rgb fill;
  bool outline = false;  // thin grey outline (legend box, plot frame)
  bool filled = true;
};
struct TextItem {
  enum class Anchor { kStart, kMiddle, kEnd };
  Eigen::Vector2d px = Eigen::Vector2d::Zero();  // baseline point (of the rotated text too)
  std::string text;
  double size_px = 12;
  Anchor anchor = Anchor::kStart;
  bool vertical = false;  // rotated 90 degrees counter-clockwise (y-axis label)
  Rgb color;
};
using SceneItem = std::variant<PathItem, DotsItem, RectItem, TextItem>;
struct Scene {
  int width_px = 0, height_px = 0;
  std::vector<SceneItem> items;
};

// Places the panels, axes, ticks, labels, legend and data in pixels. Axis ranges cover the
// data (5 % margin) and, for bars, zero.
Scene layoutFigure(const Figure& f);

// Well-formed standalone SVG 1.1 (XML-escaped text).
std::string sceneToSvg(const Scene& s);

// The scene drawn with OpenCV (anti-aliased), white background, CV_8UC3 BGR.
cv::Mat sceneToImage(const Scene& s);

// Rough text width used by the layout (legend boxes, margins): 0.7 em per character (OpenCV's
// Hershey font; wider than most SVG fonts).
double textWidthPx(const std::string& text, double size_px);

}  // namespace svslam::plot
