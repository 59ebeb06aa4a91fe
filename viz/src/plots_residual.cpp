// Residual heat maps from a diagnostics log (figures.h): mean |residual| per (time, raw row) bin and
// per image cell. A rolling shutter left unmodelled shows as residuals that grow away from the middle
// row y0 while the camera moves fast; vignetting shows as a ring in the image map. Residuals are in grey
// levels of the 8-bit image scale (0-255), as the photometric thresholds are.
#include <algorithm>
#include <cmath>

#include "canvas.h"
#include "rsvio/core/error.h"
#include "rsvio/viz/figures.h"

namespace rsvio::viz {
using namespace detail;

namespace {

void saveOrThrow(const Canvas& c, const std::string& path) {
  std::string why;
  if (!c.save(path, &why)) throw Error(why);
}

struct Bins {
  int nx = 0, ny = 0;
  std::vector<double> sum;
  std::vector<int> count;
  Bins(int nx_, int ny_) : nx(nx_), ny(ny_), sum(static_cast<size_t>(nx_) * ny_, 0.0), count(sum.size(), 0) {}
  void add(int ix, int iy, double v) {
    if (ix < 0 || iy < 0 || ix >= nx || iy >= ny) return;
    sum[iy * nx + ix] += v;
    ++count[iy * nx + ix];
  }
  double mean(int ix, int iy) const {
    const int k = iy * nx + ix;
    return count[k] > 0 ? sum[k] / count[k] : kNaN;
  }
  // Colour limit: the 98th percentile of the cell means, so one hot cell does not wash out the rest.
  double robustMax() const {
    std::vector<double> m;
    for (int iy = 0; iy < ny; ++iy) {
      for (int ix = 0; ix < nx; ++ix) {
        if (count[iy * nx + ix] > 0) m.push_back(mean(ix, iy));
      }
    }
    if (m.empty()) return 1.0;
    std::sort(m.begin(), m.end());
    const double v = m[static_cast<size_t>(0.98 * (m.size() - 1))];
    return v > 0 ? v : std::max(m.back(), 1e-6);
  }
};

double value(const ResidualObservation& o, bool weighted) {
  return weighted ? std::abs(o.weight * o.residual) : std::abs(o.residual);
}

// Draws the bins as cells of `pa` whose axes span [x_lo, x_hi] x [y_lo, y_hi], then the colour bar.
void drawHeat(Canvas& c, PlotArea& pa, const Bins& b, double x_lo, double x_hi, double y_lo, double y_hi, double vmax,
              const std::string& bar_label) {
  for (int iy = 0; iy < b.ny; ++iy) {
    for (int ix = 0; ix < b.nx; ++ix) {
      const double m = b.mean(ix, iy);
      const cv::Point2d p0 = pa.toPx(x_lo + (x_hi - x_lo) * ix / b.nx, y_lo + (y_hi - y_lo) * iy / b.ny);
      const cv::Point2d p1 = pa.toPx(x_lo + (x_hi - x_lo) * (ix + 1) / b.nx, y_lo + (y_hi - y_lo) * (iy + 1) / b.ny);
      const int x0 = static_cast<int>(std::floor(std::min(p0.x, p1.x))), x1 = static_cast<int>(std::ceil(std::max(p0.x, p1.x)));
      const int y0 = static_cast<int>(std::floor(std::min(p0.y, p1.y))), y1 = static_cast<int>(std::ceil(std::max(p0.y, p1.y)));
      c.fillRect(cv::Rect(x0, y0, std::max(1, x1 - x0), std::max(1, y1 - y0)), std::isnan(m) ? kWhite : viridis(m / vmax));
    }
  }
  const double f = c.baseFont();
  const cv::Rect& a = pa.area();
  colourBar(c, cv::Rect(a.x + a.width + static_cast<int>(f * 1.2), a.y + static_cast<int>(f), static_cast<int>(f),
                        a.height - static_cast<int>(f)),
            viridis, 0, vmax, false, "mean " + bar_label + " [grey levels]");
}

}  // namespace

void renderResidualRowTime(const ResidualMapInput& in, const std::string& path, FigureSize size) {
  Canvas c(size.width, size.height);
  const std::string label = in.weighted ? "|w r|" : "|r|";
  if (in.obs.empty() || in.image_height <= 0) {
    messageFigure(c, "Residual against image row and time", {"no residuals in the diagnostics log"}, kMuted);
    saveOrThrow(c, path);
    return;
  }
  int64_t t0 = in.obs.front().t_ns, t1 = t0;
  for (const auto& o : in.obs) {
    t0 = std::min(t0, o.t_ns);
    t1 = std::max(t1, o.t_ns);
  }
  const double span_s = std::max(1e-3, (t1 - t0) * 1e-9);
  const double y0 = 0.5 * (in.image_height - 1);
  // No more time bins than frames: a bin between two frames would be an empty stripe.
  std::vector<int64_t> stamps;
  for (const auto& o : in.obs) stamps.push_back(o.t_ns);
  std::sort(stamps.begin(), stamps.end());
  const int frames = static_cast<int>(std::unique(stamps.begin(), stamps.end()) - stamps.begin());
  const int nt = std::max(1, std::min(in.time_bins, frames)), nr = std::max(1, std::min(in.row_bins, in.image_height));
  Bins b(nt, nr);
  for (const auto& o : in.obs) {
    const double row = y0 + o.row_minus_y0;
    const int it = t1 > t0 ? std::min(nt - 1, static_cast<int>(static_cast<double>(o.t_ns - t0) / (t1 - t0) * nt)) : 0;
    const int ir = static_cast<int>(std::floor((row + 0.5) / in.image_height * nr));
    b.add(it, ir, value(o, in.weighted));
  }
  const double f = c.baseFont();
  const cv::Rect area = plotRect(c, static_cast<int>(f * 6));
  // Pixel rows span [-0.5, h - 0.5]; row 0 is drawn at the top, as in the image.
  PlotArea pa(c, area, Axis{0, span_s, false, false, "time [s]"},
              Axis{-0.5, in.image_height - 0.5, false, true, "raw image row [px]"});
  drawHeat(c, pa, b, 0, span_s, -0.5, in.image_height - 0.5, b.robustMax(), label);
  pa.drawAxes("Mean " + label + " by raw row and time (" + std::to_string(in.obs.size()) + " observations)", 8, 6, false);
  pa.hline(y0, kWhite, 1, true);
  // The dashed line is explained in the figure itself, not only in a caption elsewhere.
  c.text("dashed: middle row y0 = " + formatNumber(y0) + " (the row the image timestamp refers to)",
         c.width() - f * 0.5, c.height() - f * 0.3, f * 0.75, kMuted, HAlign::kRight, VAlign::kBottom);
  saveOrThrow(c, path);
}

void renderResidualImage(const ResidualMapInput& in, const std::string& path, FigureSize size) {
  Canvas c(size.width, size.height);
  const std::string label = in.weighted ? "|w r|" : "|r|";
  if (in.obs.empty() || in.image_width <= 0 || in.image_height <= 0) {
    messageFigure(c, "Residual over the image", {"no residuals in the diagnostics log"}, kMuted);
    saveOrThrow(c, path);
    return;
  }
  const int nx = std::max(1, std::min(in.x_bins, in.image_width));
  const int ny = std::max(1, static_cast<int>(std::lround(nx * static_cast<double>(in.image_height) / in.image_width)));
  Bins b(nx, ny);
  for (const auto& o : in.obs) {
    const int ix = static_cast<int>(std::floor((o.x + 0.5) / in.image_width * nx));
    const int iy = static_cast<int>(std::floor((o.y + 0.5) / in.image_height * ny));
    b.add(ix, iy, value(o, in.weighted));
  }
  const double f = c.baseFont();
  cv::Rect area = plotRect(c, static_cast<int>(f * 6));
  // Keep the image's aspect ratio.
  const double s = std::min(static_cast<double>(area.width) / in.image_width, static_cast<double>(area.height) / in.image_height);
  const int w = static_cast<int>(in.image_width * s), h = static_cast<int>(in.image_height * s);
  area = cv::Rect(area.x + (area.width - w) / 2, area.y + (area.height - h) / 2, std::max(10, w), std::max(10, h));
  PlotArea pa(c, area, Axis{-0.5, in.image_width - 0.5, false, false, "x [px]"},
              Axis{-0.5, in.image_height - 0.5, false, true, "y [px]"});
  drawHeat(c, pa, b, -0.5, in.image_width - 0.5, -0.5, in.image_height - 0.5, b.robustMax(), label);
  pa.drawAxes("Mean " + label + " over the image (" + std::to_string(in.obs.size()) + " observations)", 6, 5, false);
  saveOrThrow(c, path);
}

}  // namespace rsvio::viz
