// The compare colour grid (the paper's Fig. 6) and ATE per configuration (figures.h).
#include <algorithm>
#include <cmath>
#include <map>

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

int indexOf(const std::vector<std::string>& v, const std::string& s) {
  const auto it = std::find(v.begin(), v.end(), s);
  return it == v.end() ? -1 : static_cast<int>(it - v.begin());
}

// Log colour limits: the data's range widened to whole decades (at least one), unless given.
void colourLimits(const CompareGrid& g, double& lo, double& hi) {
  lo = g.lo_m;
  hi = g.hi_m;
  double dlo = INFINITY, dhi = -INFINITY;
  for (const auto& c : g.cells) {
    if (!c.failed && std::isfinite(c.ate_m) && c.ate_m > 0) {
      dlo = std::min(dlo, c.ate_m);
      dhi = std::max(dhi, c.ate_m);
    }
  }
  if (!std::isfinite(dlo)) {
    dlo = 0.01;
    dhi = 1.0;
  }
  if (!(lo > 0)) lo = std::pow(10.0, std::floor(std::log10(dlo)));
  if (!(hi > 0)) hi = std::pow(10.0, std::ceil(std::log10(dhi)));
  if (!(hi > lo)) hi = lo * 10;
}

}  // namespace

CompareGrid makeCompareGrid(const std::vector<CompareRun>& runs) {
  CompareGrid g;
  g.runs = 1;
  for (const auto& r : runs) {
    if (indexOf(g.configs, r.config) < 0) g.configs.push_back(r.config);
    if (indexOf(g.sequences, r.sequence) < 0) g.sequences.push_back(r.sequence);
    g.runs = std::max(g.runs, r.run + 1);
  }
  g.cells = runs;
  return g;
}

namespace {

// Figure size and font for a grid drawn at its natural size.
FigureSize autoGridSize(const CompareGrid& g, double& font) {
  const int ncol = std::max<int>(1, static_cast<int>(g.sequences.size()) * g.runs);
  const int nrow = std::max<int>(1, static_cast<int>(g.configs.size()));
  const double gap = g.runs > 1 ? 0.5 : 0.15;
  const double cols = ncol + gap * (std::max<int>(1, static_cast<int>(g.sequences.size())) - 1);
  const double sq = std::clamp(1100.0 / cols, 16.0, 48.0);
  font = std::clamp(sq * 0.5, 12.0, 16.0);
  Canvas probe(10, 10);
  int label_w = 0;
  for (const auto& cfg : g.configs) label_w = std::max(label_w, probe.textSize(cfg, font * 0.85).width);
  label_w = std::min(label_w, 420);
  const double w = font + label_w + font * 0.6 + sq * cols + font * 6.0 + 4;
  const double h = font * 4.2 + std::max(sq * nrow, font * 8.0) + font * 3.0 + 4;  // room for the colour bar
  return {static_cast<int>(std::ceil(w)), static_cast<int>(std::ceil(h))};
}

}  // namespace

void renderCompareGrid(const CompareGrid& g, const std::string& path, FigureSize size) {
  double font = 0;
  if (size.width <= 0 || size.height <= 0) size = autoGridSize(g, font);
  Canvas c(size.width, size.height);
  if (font > 0) c.setBaseFont(font);
  if (g.configs.empty() || g.sequences.empty()) {
    messageFigure(c, g.title, {"no runs to compare"}, kMuted);
    saveOrThrow(c, path);
    return;
  }
  double lo, hi;
  colourLimits(g, lo, hi);
  const double f = c.baseFont();
  int label_w = 0;
  for (const auto& cfg : g.configs) label_w = std::max(label_w, c.textSize(cfg, f * 0.85).width);
  label_w = std::min(label_w, size.width / 3);
  const int nseq = static_cast<int>(g.sequences.size()), nrow = static_cast<int>(g.configs.size());
  const int ncol = nseq * g.runs;
  const double left = f + label_w + f * 0.6, right = f * 6.0, top = f * 4.2, bottom = f * 3.0;
  const double group_gap_frac = g.runs > 1 ? 0.5 : 0.15;  // sequence groups stand apart, in squares
  const double sq = std::max(2.0, std::min((size.width - left - right) / (ncol + group_gap_frac * (nseq - 1)),
                                           (size.height - top - bottom) / nrow));
  const double grid_w = sq * (ncol + group_gap_frac * (nseq - 1)), grid_h = sq * nrow;
  const double x0 = left + std::max(0.0, (size.width - left - right - grid_w) / 2), y0 = top;
  auto cellRect = [&](int row, int seq, int run) {
    const double x = x0 + sq * (seq * g.runs + run + seq * group_gap_frac), y = y0 + sq * row;
    const int inset = sq >= 8 ? 1 : 0;  // a thin white seam between squares
    return cv::Rect(static_cast<int>(std::lround(x)) + inset, static_cast<int>(std::lround(y)) + inset,
                    std::max(1, static_cast<int>(std::lround(sq)) - 2 * inset),
                    std::max(1, static_cast<int>(std::lround(sq)) - 2 * inset));
  };
  c.text(c.fit(g.title, f, size.width - 8), size.width / 2.0, f * 0.5, f, kText, HAlign::kCenter, VAlign::kTop);
  // Empty slots (a run that never happened) stay light so a missing run is not mistaken for a result.
  for (int r = 0; r < nrow; ++r) {
    for (int s = 0; s < nseq; ++s) {
      for (int k = 0; k < g.runs; ++k) c.rect(cellRect(r, s, k), kGrid);
    }
  }
  for (const auto& cell : g.cells) {
    const int r = indexOf(g.configs, cell.config), s = indexOf(g.sequences, cell.sequence);
    if (r < 0 || s < 0 || cell.run < 0 || cell.run >= g.runs) continue;
    const cv::Rect rc = cellRect(r, s, cell.run);
    if (cell.failed) {
      c.fillRect(rc, kWhite);
      c.rect(rc, kMuted);
      const int t = sq >= 24 ? 2 : 1;
      c.line({double(rc.x + 2), double(rc.y + 2)}, {double(rc.x + rc.width - 3), double(rc.y + rc.height - 3)}, kRed, t);
      c.line({double(rc.x + rc.width - 3), double(rc.y + 2)}, {double(rc.x + 2), double(rc.y + rc.height - 3)}, kRed, t);
    } else if (std::isfinite(cell.ate_m)) {
      c.fillRect(rc, errorMap(normalise(cell.ate_m, lo, hi, true)));
    } else {
      c.fillRect(rc, kNoData);
    }
  }
  for (int r = 0; r < nrow; ++r) {
    c.text(c.fit(g.configs[r], f * 0.85, label_w), left - f * 0.6, y0 + sq * (r + 0.5), f * 0.85, kText, HAlign::kRight,
           VAlign::kMiddle);
  }
  for (int s = 0; s < nseq; ++s) {
    const cv::Rect a = cellRect(0, s, 0), b = cellRect(0, s, g.runs - 1);
    const double cx = 0.5 * (a.x + b.x + b.width), gw = b.x + b.width - a.x + sq * group_gap_frac;
    c.text(c.fit(g.sequences[s], f * 0.8, static_cast<int>(std::max(gw, 3 * f))), cx, y0 - f * 0.5, f * 0.8, kText,
           HAlign::kCenter, VAlign::kBottom);
  }
  // Legend for the special squares, under the grid.
  const double ly = y0 + grid_h + f * 1.2;
  const int ls = static_cast<int>(f);
  cv::Rect fr(static_cast<int>(x0), static_cast<int>(ly), ls, ls);
  c.fillRect(fr, kWhite);
  c.rect(fr, kMuted);
  c.line({double(fr.x + 1), double(fr.y + 1)}, {double(fr.x + ls - 2), double(fr.y + ls - 2)}, kRed);
  c.line({double(fr.x + ls - 2), double(fr.y + 1)}, {double(fr.x + 1), double(fr.y + ls - 2)}, kRed);
  const auto t1 = c.text("failed", fr.x + ls + f * 0.4, fr.y + ls / 2.0, f * 0.8, kText, HAlign::kLeft, VAlign::kMiddle);
  cv::Rect nr(static_cast<int>(t1.x + t1.width + f * 1.2), fr.y, ls, ls);
  c.fillRect(nr, kNoData);
  c.text("no ground truth", nr.x + ls + f * 0.4, nr.y + ls / 2.0, f * 0.8, kText, HAlign::kLeft, VAlign::kMiddle);
  // A short grid (few configurations) still gets a readable colour bar.
  const double bar_h = std::max(grid_h, std::min(size.height - y0 - f, f * 8.0));
  colourBar(c, cv::Rect(static_cast<int>(x0 + grid_w + f * 1.2), static_cast<int>(y0), static_cast<int>(std::max(6.0, f * 0.9)),
                        static_cast<int>(bar_h)),
            errorMap, lo, hi, true, "ATE [m]");
  saveOrThrow(c, path);
}

void renderAtePerConfig(const CompareGrid& g, const std::string& path, FigureSize size) {
  Canvas c(size.width, size.height);
  const int n = static_cast<int>(g.configs.size());
  std::vector<std::vector<double>> values(n);
  std::vector<int> failed(n, 0);
  for (const auto& cell : g.cells) {
    const int r = indexOf(g.configs, cell.config);
    if (r < 0) continue;
    if (cell.failed) ++failed[r];
    else if (std::isfinite(cell.ate_m) && cell.ate_m > 0) values[r].push_back(cell.ate_m);
  }
  double lo = INFINITY, hi = -INFINITY;
  for (const auto& v : values) {
    for (double x : v) {
      lo = std::min(lo, x);
      hi = std::max(hi, x);
    }
  }
  if (n == 0 || !std::isfinite(lo)) {
    messageFigure(c, "ATE per configuration", {n == 0 ? "no runs" : "no run has an ATE (all failed or no ground truth)"}, kMuted);
    saveOrThrow(c, path);
    return;
  }
  const bool log_axis = hi / lo > 10.0;
  if (log_axis) {
    lo = std::pow(10.0, std::floor(std::log10(lo)));
    hi = std::pow(10.0, std::ceil(std::log10(hi)));
  } else {
    padRange(lo, hi, 0.08, true);
  }
  const double f = c.baseFont();
  cv::Rect area = plotRect(c);
  area.height -= static_cast<int>(f * 1.4);  // room for the "n failed" line
  PlotArea pa(c, area, Axis{-0.5, n - 0.5, false, false, ""}, Axis{lo, hi, log_axis, false, "ATE [m]"});
  pa.drawAxes("ATE per configuration (" + std::to_string(g.sequences.size()) + " sequence(s) x " +
                  std::to_string(g.runs) + " run(s))",
              0, 6);
  const double slot = static_cast<double>(area.width) / n;
  for (int i = 0; i < n; ++i) {
    const double cx = pa.toPx(i, lo).x;
    const Rgb colour = turbo(0.1 + 0.8 * (n > 1 ? static_cast<double>(i) / (n - 1) : 0.0));
    auto v = values[i];
    std::sort(v.begin(), v.end());
    if (!v.empty()) {
      auto q = [&](double p) {  // linear interpolation between order statistics
        const double k = p * (v.size() - 1);
        const size_t a = static_cast<size_t>(std::floor(k)), b = std::min(v.size() - 1, a + 1);
        return v[a] + (v[b] - v[a]) * (k - a);
      };
      const double q1 = q(0.25), q2 = q(0.5), q3 = q(0.75), iqr = q3 - q1;
      double wlo = v.front(), whi = v.back();
      for (double x : v) {
        if (x >= q1 - 1.5 * iqr) { wlo = x; break; }
      }
      for (auto it = v.rbegin(); it != v.rend(); ++it) {
        if (*it <= q3 + 1.5 * iqr) { whi = *it; break; }
      }
      const double hw = std::min(slot * 0.3, f * 3.0);
      const double yq1 = pa.toPx(i, q1).y, yq3 = pa.toPx(i, q3).y;
      c.line({cx, pa.toPx(i, wlo).y}, {cx, yq1}, kAxis);
      c.line({cx, yq3}, {cx, pa.toPx(i, whi).y}, kAxis);
      c.line({cx - hw / 2, pa.toPx(i, wlo).y}, {cx + hw / 2, pa.toPx(i, wlo).y}, kAxis);
      c.line({cx - hw / 2, pa.toPx(i, whi).y}, {cx + hw / 2, pa.toPx(i, whi).y}, kAxis);
      const cv::Rect box(static_cast<int>(cx - hw), static_cast<int>(std::min(yq1, yq3)), static_cast<int>(2 * hw),
                         std::max(1, static_cast<int>(std::abs(yq1 - yq3))));
      c.fillRect(box, Rgb{static_cast<uint8_t>(155 + colour.r * 100 / 255), static_cast<uint8_t>(155 + colour.g * 100 / 255),
                          static_cast<uint8_t>(155 + colour.b * 100 / 255)});
      c.rect(box, kAxis);
      c.line({cx - hw, pa.toPx(i, q2).y}, {cx + hw, pa.toPx(i, q2).y}, kBlack, 2);
      // Every run as a dot, spread deterministically across the box so equal values stay visible.
      for (size_t k = 0; k < values[i].size(); ++k) {
        const double jitter = v.size() > 1 ? (static_cast<double>((k * 7) % v.size()) / (v.size() - 1) - 0.5) : 0.0;
        c.circle({cx + jitter * hw * 1.2, pa.toPx(i, values[i][k]).y}, std::max(2.0, f * 0.2), colour);
      }
    }
    const double ty = area.y + area.height + f * 0.5;
    c.text(c.fit(g.configs[i], f * 0.85, static_cast<int>(slot * 0.95)), cx, ty, f * 0.85, kText, HAlign::kCenter, VAlign::kTop);
    const std::string note = failed[i] > 0 ? std::to_string(failed[i]) + " failed" : std::to_string(v.size()) + " run(s)";
    c.text(note, cx, ty + f * 1.4, f * 0.75, failed[i] > 0 ? kRed : kMuted, HAlign::kCenter, VAlign::kTop);
  }
  saveOrThrow(c, path);
}

}  // namespace rsvio::viz
