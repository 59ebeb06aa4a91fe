// Time-series panels, error over time and the plan view of a trajectory (figures.h).
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

bool hasData(const Panel& p) {
  for (const auto& s : p.series) {
    for (size_t i = 0; i < std::min(s.x.size(), s.y.size()); ++i) {
      if (std::isfinite(s.x[i]) && std::isfinite(s.y[i])) return true;
    }
  }
  return false;
}

void finiteRange(const std::vector<double>& v, double& lo, double& hi) {
  for (double x : v) {
    if (!std::isfinite(x)) continue;
    lo = std::min(lo, x);
    hi = std::max(hi, x);
  }
}

}  // namespace

void renderPanels(const std::vector<Panel>& panels, const std::string& message, const std::string& path,
                  FigureSize size) {
  Canvas c(size.width, size.height);
  std::vector<const Panel*> shown;
  for (const auto& p : panels) {
    if (hasData(p)) shown.push_back(&p);
  }
  if (shown.empty()) {
    messageFigure(c, panels.empty() ? "No data" : panels.front().title,
                  {message.empty() ? "nothing to plot" : message}, message.empty() ? kMuted : kRed);
    saveOrThrow(c, path);
    return;
  }
  const int n = static_cast<int>(shown.size());
  for (int i = 0; i < n; ++i) {
    const Panel& p = *shown[i];
    const int top = size.height * i / n, bottom = size.height * (i + 1) / n;
    const double f = c.baseFont();
    const cv::Rect area(static_cast<int>(f * 5.0), static_cast<int>(f * 2.2), size.width - static_cast<int>(f * 6.2),
                        (bottom - top) - static_cast<int>(f * 2.2) - static_cast<int>(f * 3.4));
    if (area.height < 10 || area.width < 10) continue;
    double xlo = INFINITY, xhi = -INFINITY, ylo = INFINITY, yhi = -INFINITY;
    for (const auto& s : p.series) {
      finiteRange(s.x, xlo, xhi);
      finiteRange(s.y, ylo, yhi);
    }
    for (const auto& h : p.hlines) {
      if (std::isfinite(h.second)) {
        ylo = std::min(ylo, h.second);
        yhi = std::max(yhi, h.second);
      }
    }
    if (!(xhi > xlo)) {
      xlo -= 0.5;
      xhi += 0.5;
    }
    padRange(ylo, yhi, 0.06, p.y_from_zero);
    Axis ax{xlo, xhi, false, false, p.x_label};
    Axis ay{ylo, yhi, false, false, p.y_label};
    PlotArea pa(c, area + cv::Point(0, top), ax, ay);
    pa.drawAxes(p.title);
    std::vector<std::pair<std::string, Rgb>> legend;
    std::vector<bool> dashed;
    for (const auto& h : p.hlines) {
      if (!std::isfinite(h.second)) continue;
      pa.hline(h.second, kRed, 1, true);
      legend.emplace_back(h.first, kRed);
      dashed.push_back(true);  // reference lines are drawn dashed: so is their swatch
    }
    for (const auto& s : p.series) {
      pa.series(s.x, s.y, s.colour, 2);
      if (!s.name.empty()) {
        legend.emplace_back(s.name, s.colour);
        dashed.push_back(false);
      }
    }
    if (legend.size() > 1 || (legend.size() == 1 && !p.hlines.empty())) pa.legend(legend, dashed);
  }
  saveOrThrow(c, path);
}

void renderErrorOverTime(const ErrorSeries& e, const std::string& path, FigureSize size) {
  Panel p;
  p.title = e.title;
  p.x_label = "time [s]";
  p.y_label = "position error [m]";
  p.y_from_zero = true;
  // Break the line over gaps in the estimate (more than 5x the median step), so a stretch without poses
  // is not drawn as a steep straight line.
  Series s{"error after alignment", {}, {}, kBlue};
  std::vector<double> steps;
  for (size_t i = 1; i < e.t_s.size(); ++i) steps.push_back(e.t_s[i] - e.t_s[i - 1]);
  double median_step = 0;
  if (!steps.empty()) {
    std::nth_element(steps.begin(), steps.begin() + steps.size() / 2, steps.end());
    median_step = steps[steps.size() / 2];
  }
  for (size_t i = 0; i < std::min(e.t_s.size(), e.err_m.size()); ++i) {
    if (i > 0 && median_step > 0 && e.t_s[i] - e.t_s[i - 1] > 5 * median_step) {
      s.x.push_back(kNaN);
      s.y.push_back(kNaN);
    }
    s.x.push_back(e.t_s[i]);
    s.y.push_back(e.err_m[i]);
  }
  p.series.push_back(std::move(s));
  if (std::isfinite(e.ate_rmse_m)) p.hlines.emplace_back("ATE RMSE " + formatNumber(e.ate_rmse_m) + " m", e.ate_rmse_m);
  renderPanels({p}, e.message.empty() ? "no trajectory errors (no ground truth?)" : e.message, path, size);
}

void renderPlanTrajectory(const PlanTrajectory& p, const std::string& path, FigureSize size) {
  Canvas c(size.width, size.height);
  double xlo = INFINITY, xhi = -INFINITY, ylo = INFINITY, yhi = -INFINITY;
  finiteRange(p.gt_x, xlo, xhi);
  finiteRange(p.est_x, xlo, xhi);
  finiteRange(p.gt_y, ylo, yhi);
  finiteRange(p.est_y, ylo, yhi);
  if (!(xhi >= xlo) || !(yhi >= ylo)) {
    messageFigure(c, p.title, {p.message.empty() ? "no trajectory" : p.message}, kRed);
    saveOrThrow(c, path);
    return;
  }
  const bool coloured = !p.est_err_m.empty() && p.est_err_m.size() == p.est_x.size();
  double emax = 0;
  if (coloured) {
    for (double e : p.est_err_m) {
      if (std::isfinite(e)) emax = std::max(emax, e);
    }
    if (!(emax > 0)) emax = 1e-3;
  }
  const double f = c.baseFont();
  cv::Rect area = plotRect(c, coloured ? static_cast<int>(f * 6) : 0);
  padRange(xlo, xhi, 0.05, false);
  padRange(ylo, yhi, 0.05, false);
  // Equal scale on both axes: widen the shorter span around its centre.
  const double sx = (xhi - xlo) / area.width, sy = (yhi - ylo) / area.height, s = std::max(sx, sy);
  const double cx = 0.5 * (xlo + xhi), cy = 0.5 * (ylo + yhi);
  xlo = cx - 0.5 * s * area.width;
  xhi = cx + 0.5 * s * area.width;
  ylo = cy - 0.5 * s * area.height;
  yhi = cy + 0.5 * s * area.height;
  PlotArea pa(c, area, Axis{xlo, xhi, false, false, "x [" + p.unit + "]"}, Axis{ylo, yhi, false, false, "y [" + p.unit + "]"});
  pa.drawAxes(p.title);
  std::vector<std::pair<std::string, Rgb>> legend;
  if (!p.gt_x.empty()) {
    pa.series(p.gt_x, p.gt_y, kMuted, 2);
    legend.emplace_back("ground truth", kMuted);
  }
  if (coloured) {
    for (size_t i = 1; i < p.est_x.size(); ++i) {
      const double e = 0.5 * (p.est_err_m[i - 1] + p.est_err_m[i]);
      c.line(pa.toPx(p.est_x[i - 1], p.est_y[i - 1]), pa.toPx(p.est_x[i], p.est_y[i]), errorMap(e / emax), 2);
    }
    legend.emplace_back("estimate (colour = error)", errorMap(0.15));
    colourBar(c, cv::Rect(area.x + area.width + static_cast<int>(f * 1.2), area.y + static_cast<int>(f), static_cast<int>(f),
                          area.height - static_cast<int>(f)),
              errorMap, 0, emax, false, "error [m]");
  } else {
    pa.series(p.est_x, p.est_y, kBlue, 2);
    legend.emplace_back("estimate", kBlue);
  }
  pa.legend(legend);
  saveOrThrow(c, path);
}

}  // namespace rsvio::viz
