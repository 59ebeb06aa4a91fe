// 2D drawing kit (canvas.h).
#include "canvas.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <opencv2/imgproc.hpp>
#ifdef RSVIO_VIZ_HAVE_FREETYPE
#include <opencv2/freetype.hpp>
#endif

#include "rsvio/core/error.h"
#include "rsvio/io/image_file.h"

namespace rsvio::viz::detail {

cv::Scalar bgr(const Rgb& c) { return cv::Scalar(c.b, c.g, c.r); }

struct Canvas::Font {
#ifdef RSVIO_VIZ_HAVE_FREETYPE
  cv::Ptr<cv::freetype::FreeType2> ft;
#endif
  bool truetype() const {
#ifdef RSVIO_VIZ_HAVE_FREETYPE
    return !ft.empty();
#else
    return false;
#endif
  }
};

namespace {

[[maybe_unused]] const char* findFontFile() {
  static const char* kCandidates[] = {"/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
                                      "/usr/share/fonts/dejavu/DejaVuSans.ttf",
                                      "/usr/share/fonts/TTF/DejaVuSans.ttf"};
  for (const char* f : kCandidates) {
    std::error_code ec;
    if (std::filesystem::exists(f, ec)) return f;
  }
  return nullptr;
}

// Hershey's cap height is about 22 px at scale 1; TrueType's ascent is about 0.8 of the pixel height.
double hersheyScale(double px) { return 0.8 * px / 22.0; }
int hersheyThickness(double px) { return px >= 22 ? 2 : 1; }

}  // namespace

Canvas::Canvas(int width, int height, Rgb background)
    : img_(std::max(1, height), std::max(1, width), CV_8UC3, bgr(background)), font_(std::make_unique<Font>()) {
#ifdef RSVIO_VIZ_HAVE_FREETYPE
  if (const char* f = findFontFile()) {
    try {
      font_->ft = cv::freetype::createFreeType2();
      font_->ft->loadFontData(f, 0);
    } catch (const cv::Exception&) {
      font_->ft.release();
    }
  }
#endif
}

Canvas::~Canvas() = default;

double Canvas::baseFont() const {
  if (base_font_ > 0) return base_font_;
  return std::clamp(std::min(width() / 1.4, static_cast<double>(height())) / 38.0, 9.0, 22.0);
}

cv::Size Canvas::textSize(const std::string& s, double px, int* descent) const {
  int base = 0;
  cv::Size sz;
#ifdef RSVIO_VIZ_HAVE_FREETYPE
  if (font_->truetype()) {
    sz = font_->ft->getTextSize(s, static_cast<int>(std::lround(px)), -1, &base);
  } else
#endif
  {
    sz = cv::getTextSize(s, cv::FONT_HERSHEY_SIMPLEX, hersheyScale(px), hersheyThickness(px), &base);
  }
  if (descent) *descent = base;
  return sz;
}

cv::Rect Canvas::text(const std::string& s, double x, double y, double px, Rgb colour, HAlign h, VAlign v) {
  if (s.empty()) return {};
  int descent = 0;
  const cv::Size sz = textSize(s, px, &descent);
  double bx = x, by = y;  // baseline-left
  if (h == HAlign::kCenter) bx -= sz.width / 2.0;
  if (h == HAlign::kRight) bx -= sz.width;
  if (v == VAlign::kTop) by += sz.height;
  if (v == VAlign::kMiddle) by += sz.height / 2.0;
  if (v == VAlign::kBottom) by -= descent;
  const cv::Point org(static_cast<int>(std::lround(bx)), static_cast<int>(std::lround(by)));
#ifdef RSVIO_VIZ_HAVE_FREETYPE
  if (font_->truetype()) {
    font_->ft->putText(img_, s, org, static_cast<int>(std::lround(px)), bgr(colour), -1, cv::LINE_AA, true);
  } else
#endif
  {
    cv::putText(img_, s, org, cv::FONT_HERSHEY_SIMPLEX, hersheyScale(px), bgr(colour), hersheyThickness(px), cv::LINE_AA);
  }
  return {org.x, org.y - sz.height, sz.width, sz.height + descent};
}

void Canvas::textVertical(const std::string& s, double x, double y, double px, Rgb colour) {
  int descent = 0;
  const cv::Size sz = textSize(s, px, &descent);
  const int w = sz.width + 4, hgt = sz.height + descent + 4;
  // Draw on a patch of the current background, rotate it, and paste it: no alpha needed.
  const int cx = std::clamp(static_cast<int>(x), 0, img_.cols - 1), cy = std::clamp(static_cast<int>(y), 0, img_.rows - 1);
  const cv::Vec3b bg = img_.at<cv::Vec3b>(cy, cx);
  Canvas patch(w, hgt, Rgb{bg[2], bg[1], bg[0]});
  patch.text(s, 2, 2 + sz.height, px, colour);
  cv::Mat rotated;
  cv::rotate(patch.image(), rotated, cv::ROTATE_90_COUNTERCLOCKWISE);
  cv::Rect dst(static_cast<int>(std::lround(x - rotated.cols / 2.0)), static_cast<int>(std::lround(y - rotated.rows / 2.0)),
               rotated.cols, rotated.rows);
  const cv::Rect clipped = dst & cv::Rect(0, 0, img_.cols, img_.rows);
  if (clipped.area() <= 0) return;
  rotated(cv::Rect(clipped.x - dst.x, clipped.y - dst.y, clipped.width, clipped.height)).copyTo(img_(clipped));
}

std::string Canvas::fit(const std::string& s, double px, int max_width) const {
  if (textSize(s, px).width <= max_width) return s;
  std::string t = s;
  while (t.size() > 1 && textSize(t + "...", px).width > max_width) t.pop_back();
  return t + "...";
}

void Canvas::line(cv::Point2d a, cv::Point2d b, Rgb c, int thickness) {
  constexpr int kShift = 4;  // sub-pixel precision
  auto fx = [](cv::Point2d p) { return cv::Point(static_cast<int>(std::lround(p.x * 16)), static_cast<int>(std::lround(p.y * 16))); };
  cv::line(img_, fx(a), fx(b), bgr(c), thickness, cv::LINE_AA, kShift);
}

void Canvas::polyline(const std::vector<cv::Point2d>& pts, Rgb c, int thickness) {
  if (pts.size() < 2) return;
  std::vector<cv::Point> p;
  p.reserve(pts.size());
  for (const auto& q : pts) p.emplace_back(static_cast<int>(std::lround(q.x * 16)), static_cast<int>(std::lround(q.y * 16)));
  cv::polylines(img_, p, false, bgr(c), thickness, cv::LINE_AA, 4);
}

void Canvas::fillRect(const cv::Rect& r, Rgb c) { cv::rectangle(img_, r, bgr(c), cv::FILLED); }
void Canvas::rect(const cv::Rect& r, Rgb c, int thickness) { cv::rectangle(img_, r, bgr(c), thickness); }
void Canvas::circle(cv::Point2d p, double radius, Rgb c, bool filled) {
  cv::circle(img_, cv::Point(static_cast<int>(std::lround(p.x * 16)), static_cast<int>(std::lround(p.y * 16))),
             static_cast<int>(std::lround(radius * 16)), bgr(c), filled ? cv::FILLED : 1, cv::LINE_AA, 4);
}

bool Canvas::save(const std::string& path, std::string* why) const {
  try {
    io::writePng(path, img_, 1);  // zlib level 1: fast, as cv::imwrite's default was
    return true;
  } catch (const Error& e) {
    if (why) *why = e.what();  // "<path>: cannot write PNG: ..."
  }
  return false;
}

double niceNumber(double v) {
  if (!(v > 0) || !std::isfinite(v)) return 1.0;
  const double e = std::floor(std::log10(v));
  const double f = v / std::pow(10.0, e);
  const double nf = f < 1.5 ? 1 : f < 3.5 ? 2 : f < 7.5 ? 5 : 10;
  return nf * std::pow(10.0, e);
}

std::vector<double> niceTicks(double lo, double hi, int max_ticks) {
  std::vector<double> t;
  if (!(hi > lo) || !std::isfinite(lo) || !std::isfinite(hi)) return t;
  const double raw = (hi - lo) / std::max(1, max_ticks);
  double step = niceNumber(raw);
  if (step < raw) step = niceNumber(raw * 1.6);
  for (double v = std::ceil(lo / step - 1e-9) * step; v <= hi + 1e-9 * step; v += step) t.push_back(std::abs(v) < 1e-12 * step ? 0.0 : v);
  return t;
}

std::vector<double> logTicks(double lo, double hi) {
  std::vector<double> t;
  if (!(lo > 0) || !(hi > lo)) return t;
  const int e0 = static_cast<int>(std::floor(std::log10(lo))), e1 = static_cast<int>(std::ceil(std::log10(hi)));
  const bool dense = e1 - e0 <= 2;  // few decades: 1, 2, 5 in each
  for (int e = e0; e <= e1; ++e) {
    for (double m : dense ? std::vector<double>{1, 2, 5} : std::vector<double>{1}) {
      const double v = m * std::pow(10.0, e);
      if (v >= lo * (1 - 1e-9) && v <= hi * (1 + 1e-9)) t.push_back(v);
    }
  }
  return t;
}

std::string formatNumber(double v) {
  char buf[32];
  const double a = std::abs(v);
  if (a == 0) return "0";
  if (a >= 1e5 || a < 1e-3) std::snprintf(buf, sizeof buf, "%.0e", v);
  else std::snprintf(buf, sizeof buf, "%.4g", v);
  return buf;
}

void padRange(double& lo, double& hi, double fraction, bool include_zero) {
  if (!std::isfinite(lo) || !std::isfinite(hi)) {
    lo = 0;
    hi = 1;
  }
  if (include_zero) {
    lo = std::min(lo, 0.0);
    hi = std::max(hi, 0.0);
  }
  if (hi - lo < 1e-12) {
    const double d = std::max(std::abs(hi) * 0.1, 1e-3);
    lo -= d;
    hi += d;
  }
  const double pad = (hi - lo) * fraction;
  if (!(include_zero && lo == 0)) lo -= pad;
  hi += pad;
}

PlotArea::PlotArea(Canvas& c, cv::Rect area, Axis x, Axis y) : c_(c), area_(area), x_(std::move(x)), y_(std::move(y)) {}

double PlotArea::mapX(double x) const {
  const double t = normalise(x, x_.lo, x_.hi, x_.log);
  return area_.x + area_.width * (x_.flip ? 1.0 - t : t);
}
double PlotArea::mapY(double y) const {
  const double t = normalise(y, y_.lo, y_.hi, y_.log);
  return area_.y + area_.height * (y_.flip ? t : 1.0 - t);
}
cv::Point2d PlotArea::toPx(double x, double y) const { return {mapX(x), mapY(y)}; }

void PlotArea::drawAxes(const std::string& title, int max_x_ticks, int max_y_ticks, bool grid) {
  const double f = c_.baseFont();
  const double tick_font = f * 0.8;
  const std::vector<double> none;
  const auto xt = max_x_ticks <= 0 ? none : x_.log ? logTicks(x_.lo, x_.hi) : niceTicks(x_.lo, x_.hi, max_x_ticks);
  const auto yt = max_y_ticks <= 0 ? none : y_.log ? logTicks(y_.lo, y_.hi) : niceTicks(y_.lo, y_.hi, max_y_ticks);
  const int x0 = area_.x, y0 = area_.y, x1 = area_.x + area_.width, y1 = area_.y + area_.height;
  if (grid) {
    for (double v : xt) c_.line({mapX(v), double(y0)}, {mapX(v), double(y1)}, kGrid);
    for (double v : yt) c_.line({double(x0), mapY(v)}, {double(x1), mapY(v)}, kGrid);
  }
  c_.rect(area_, kAxis);
  const double tl = std::max(3.0, f * 0.35);
  int widest = 0;
  for (double v : xt) {
    c_.line({mapX(v), double(y1)}, {mapX(v), y1 + tl}, kAxis);
    c_.text(formatNumber(v), mapX(v), y1 + tl + 2, tick_font, kText, HAlign::kCenter, VAlign::kTop);
  }
  for (double v : yt) {
    c_.line({x0 - tl, mapY(v)}, {double(x0), mapY(v)}, kAxis);
    const auto r = c_.text(formatNumber(v), x0 - tl - 3, mapY(v), tick_font, kText, HAlign::kRight, VAlign::kMiddle);
    widest = std::max(widest, r.width);
  }
  if (!x_.label.empty()) c_.text(x_.label, (x0 + x1) / 2.0, y1 + tl + 4 + tick_font * 1.3 + 2, f * 0.9, kText, HAlign::kCenter, VAlign::kTop);
  if (!y_.label.empty()) c_.textVertical(y_.label, x0 - tl - 6 - widest - f * 0.6, (y0 + y1) / 2.0, f * 0.9, kText);
  if (!title.empty()) c_.text(c_.fit(title, f, c_.width() - 8), (x0 + x1) / 2.0, y0 - f * 0.6, f, kText, HAlign::kCenter, VAlign::kBottom);
}

void PlotArea::series(const std::vector<double>& x, const std::vector<double>& y, Rgb colour, int thickness) {
  std::vector<cv::Point2d> run;
  auto flush = [&] {
    if (run.size() == 1) c_.circle(run[0], thickness, colour);
    c_.polyline(run, colour, thickness);
    run.clear();
  };
  for (size_t i = 0; i < std::min(x.size(), y.size()); ++i) {
    if (!std::isfinite(x[i]) || !std::isfinite(y[i]) || (y_.log && y[i] <= 0)) {
      flush();
      continue;
    }
    run.push_back(toPx(x[i], y[i]));
  }
  flush();
}

void PlotArea::hline(double y, Rgb colour, int thickness, bool dashed) {
  const double yy = mapY(y), x0 = area_.x, x1 = area_.x + area_.width;
  if (!dashed) {
    c_.line({x0, yy}, {x1, yy}, colour, thickness);
    return;
  }
  const double dash = std::max(4.0, c_.baseFont() * 0.5);
  for (double x = x0; x < x1; x += 2 * dash) c_.line({x, yy}, {std::min(x + dash, x1), yy}, colour, thickness);
}

void PlotArea::legend(const std::vector<std::pair<std::string, Rgb>>& entries, const std::vector<bool>& dashed) {
  if (entries.empty()) return;
  const double f = c_.baseFont() * 0.8;
  int w = 0;
  for (const auto& e : entries) w = std::max(w, c_.textSize(e.first, f).width);
  const int line_len = static_cast<int>(std::max(f * 2.6, 24.0)), pad = static_cast<int>(f * 0.5), row = static_cast<int>(f * 1.4);
  const int bw = pad * 3 + line_len + w, bh = pad * 2 + row * static_cast<int>(entries.size());
  const cv::Rect box(area_.x + area_.width - bw - pad, area_.y + pad, bw, bh);
  c_.fillRect(box, kWhite);
  c_.rect(box, kGrid);
  for (size_t i = 0; i < entries.size(); ++i) {
    const double y = box.y + pad + row * (i + 0.5);
    if (i < dashed.size() && dashed[i]) {
      // Three dashes with clear gaps, as hline(..., dashed) draws the line.
      const double d = 0.2 * line_len, gap = 0.2 * line_len;
      for (int k = 0; k < 3; ++k) {
        const double x = box.x + pad + k * (d + gap);
        c_.line({x, y}, {x + d, y}, entries[i].second, 2);
      }
    } else {
      c_.line({double(box.x + pad), y}, {double(box.x + pad + line_len), y}, entries[i].second, 3);
    }
    c_.text(entries[i].first, box.x + 2 * pad + line_len, y, f, kText, HAlign::kLeft, VAlign::kMiddle);
  }
}

void colourBar(Canvas& c, const cv::Rect& bar, const std::function<Rgb(double)>& map, double lo, double hi,
               bool log_scale, const std::string& label) {
  for (int i = 0; i < bar.height; ++i) {
    const double t = 1.0 - (i + 0.5) / bar.height;
    c.fillRect(cv::Rect(bar.x, bar.y + i, bar.width, 1), map(t));
  }
  c.rect(bar, kAxis);
  const double f = c.baseFont() * 0.8;
  const auto ticks = log_scale ? logTicks(lo, hi) : niceTicks(lo, hi, 5);
  for (double v : ticks) {
    const double y = bar.y + bar.height * (1.0 - normalise(v, lo, hi, log_scale));
    c.line({double(bar.x + bar.width), y}, {bar.x + bar.width + 4.0, y}, kAxis);
    c.text(formatNumber(v), bar.x + bar.width + 6.0, y, f, kText, HAlign::kLeft, VAlign::kMiddle);
  }
  if (!label.empty()) {
    // Centred on the bar, but kept inside the figure (a label with its unit is wider than the bar).
    const double w = c.textSize(label, f).width;
    const double x = std::min(bar.x + bar.width / 2.0, c.width() - w / 2.0 - 2.0);
    c.text(label, x, bar.y - f * 0.9, f, kText, HAlign::kCenter, VAlign::kBottom);
  }
}

void messageFigure(Canvas& c, const std::string& title, const std::vector<std::string>& lines, Rgb colour) {
  const double f = c.baseFont();
  c.text(c.fit(title, f * 1.1, c.width() - 16), c.width() / 2.0, c.height() * 0.35, f * 1.1, kText, HAlign::kCenter,
         VAlign::kBaseline);
  double y = c.height() * 0.35 + f * 1.9;
  for (const auto& l : lines) {
    c.text(c.fit(l, f * 0.9, c.width() - 16), c.width() / 2.0, y, f * 0.9, colour, HAlign::kCenter, VAlign::kBaseline);
    y += f * 1.4;
  }
  c.rect(cv::Rect(0, 0, c.width(), c.height()), kGrid);
}

cv::Rect plotRect(const Canvas& c, int right_extra) {
  const double f = c.baseFont();
  const int left = static_cast<int>(f * 5.0), top = static_cast<int>(f * 2.4), bottom = static_cast<int>(f * 3.6);
  const int right = static_cast<int>(f * 1.2) + right_extra;
  return {left, top, std::max(10, c.width() - left - right), std::max(10, c.height() - top - bottom)};
}

}  // namespace rsvio::viz::detail
