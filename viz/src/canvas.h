// Internal 2D drawing kit for figures: an image with text, plot areas with axes/ticks/grid, and colour
// bars. Drawn with OpenCV (no display needed, deterministic pixels); TrueType text through OpenCV's
// freetype module and DejaVu Sans when both exist, Hershey fonts otherwise.
// Coordinates are pixels, origin top-left, y down. Colours are Rgb (converted to OpenCV's BGR here).
#pragma once
#include <functional>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "rsvio/viz/colormap.h"

namespace rsvio::viz::detail {

enum class HAlign { kLeft, kCenter, kRight };
enum class VAlign { kTop, kMiddle, kBaseline, kBottom };

constexpr Rgb kBlack{0, 0, 0};
constexpr Rgb kWhite{255, 255, 255};
constexpr Rgb kAxis{60, 60, 60};
constexpr Rgb kGrid{228, 228, 228};
constexpr Rgb kText{30, 30, 30};
constexpr Rgb kMuted{110, 110, 110};
constexpr Rgb kRed{200, 30, 30};
constexpr Rgb kBlue{31, 119, 180};
constexpr Rgb kOrange{255, 127, 14};

cv::Scalar bgr(const Rgb& c);

class Canvas {
 public:
  Canvas(int width, int height, Rgb background = kWhite);
  ~Canvas();

  cv::Mat& image() { return img_; }
  int width() const { return img_.cols; }
  int height() const { return img_.rows; }
  // A font size that reads well at this figure size (px of cap height + ascenders).
  double baseFont() const;
  void setBaseFont(double px) { base_font_ = px; }  // fixed size instead of one from the figure size

  // Text of height px, anchored at (x, y) as aligned. Returns the text's box.
  cv::Rect text(const std::string& s, double x, double y, double px, Rgb colour, HAlign h = HAlign::kLeft,
                VAlign v = VAlign::kBaseline);
  // Text rotated 90 degrees counter-clockwise (reads bottom to top), centred at (x, y).
  void textVertical(const std::string& s, double x, double y, double px, Rgb colour);
  cv::Size textSize(const std::string& s, double px, int* descent = nullptr) const;
  // Shortens s with "..." until it fits max_width.
  std::string fit(const std::string& s, double px, int max_width) const;

  void line(cv::Point2d a, cv::Point2d b, Rgb c, int thickness = 1);
  void polyline(const std::vector<cv::Point2d>& pts, Rgb c, int thickness = 1);
  void fillRect(const cv::Rect& r, Rgb c);
  void rect(const cv::Rect& r, Rgb c, int thickness = 1);
  void circle(cv::Point2d p, double radius, Rgb c, bool filled = true);

  // Writes the PNG; false with a reason in *why when it fails.
  bool save(const std::string& path, std::string* why) const;

 private:
  struct Font;
  cv::Mat img_;
  std::unique_ptr<Font> font_;
  double base_font_ = 0;
};

struct Axis {
  double lo = 0, hi = 1;
  bool log = false;
  bool flip = false;  // larger values towards the bottom/left (image rows)
  std::string label;
};

std::vector<double> niceTicks(double lo, double hi, int max_ticks);
std::vector<double> logTicks(double lo, double hi);
// Short numbers for tick labels: 0.001, 0.25, 12, 1.5e+04.
std::string formatNumber(double v);
// A "nice" number (1, 2, 5 x 10^k) close to v.
double niceNumber(double v);
// lo/hi widened to include 0 where reasonable and padded by a fraction of the span.
void padRange(double& lo, double& hi, double fraction, bool include_zero);

class PlotArea {
 public:
  PlotArea(Canvas& c, cv::Rect area, Axis x, Axis y);
  cv::Point2d toPx(double x, double y) const;
  const cv::Rect& area() const { return area_; }
  // Grid, frame, ticks and tick labels, axis labels, and a title above the area. max_*_ticks = 0: none.
  void drawAxes(const std::string& title, int max_x_ticks = 8, int max_y_ticks = 6, bool grid = true);
  // Connected line; NaN values break it.
  void series(const std::vector<double>& x, const std::vector<double>& y, Rgb colour, int thickness = 2);
  void hline(double y, Rgb colour, int thickness = 1, bool dashed = false);
  // Legend box in the upper right corner of the area: a short line per named entry, dashed where
  // dashed[i] is true (the swatch looks like the line it names).
  void legend(const std::vector<std::pair<std::string, Rgb>>& entries, const std::vector<bool>& dashed = {});

 private:
  double mapX(double x) const;
  double mapY(double y) const;
  Canvas& c_;
  cv::Rect area_;
  Axis x_, y_;
};

// Vertical colour bar in `bar` with ticks and a label on its right.
void colourBar(Canvas& c, const cv::Rect& bar, const std::function<Rgb(double)>& map, double lo, double hi,
               bool log_scale, const std::string& label);

// A figure that says why there is nothing to plot (failed run, missing data).
void messageFigure(Canvas& c, const std::string& title, const std::vector<std::string>& lines, Rgb colour = kText);

// Standard margins for a single plot with title and axis labels.
cv::Rect plotRect(const Canvas& c, int right_extra = 0);

}  // namespace rsvio::viz::detail
