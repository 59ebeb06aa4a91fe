// 2D figures from plain data, so that run, compare and diagnose can each draw without knowing about
// each other: the caller fills a struct, the function writes a PNG.
//
// All functions draw with OpenCV into an image (no display needed) and throw rsvio::Error when the PNG
// cannot be written. An input with no data still gives a figure that says so (a failed run's figure is
// a picture of why it failed, not a missing file).
// Units: seconds and metres unless a struct says otherwise; colour maps from colormap.h.
#pragma once
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "rsvio/viz/colormap.h"

namespace rsvio::viz {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

struct FigureSize {
  int width = 960;
  int height = 540;
};

// ---- Time series ---------------------------------------------------------------------------------
struct Series {
  std::string name;        // legend entry (empty: no entry)
  std::vector<double> x;   // NaN breaks the line
  std::vector<double> y;
  Rgb colour{31, 119, 180};
};

struct Panel {
  std::string title;
  std::string x_label, y_label;
  std::vector<Series> series;
  std::vector<std::pair<std::string, double>> hlines;  // labelled horizontal reference lines
  bool y_from_zero = false;
};

// Panels stacked vertically, sharing the figure; `message` replaces them when none has data.
void renderPanels(const std::vector<Panel>& panels, const std::string& message, const std::string& path,
                  FigureSize size = {});

// Position error over time (one panel; ATE RMSE as a reference line).
struct ErrorSeries {
  std::string title = "Position error over time";
  std::vector<double> t_s;   // seconds from the first sample
  std::vector<double> err_m;
  double ate_rmse_m = kNaN;  // drawn as a horizontal line when finite
  std::string message;       // shown when there is no data (e.g. "run failed: <error>")
};
void renderErrorOverTime(const ErrorSeries& e, const std::string& path, FigureSize size = {});

// ---- Trajectory in plan (x-y), drawn without VTK --------------------------------------------------
struct PlanTrajectory {
  std::string title = "Trajectory, top view";
  std::vector<double> gt_x, gt_y;
  std::vector<double> est_x, est_y;
  std::vector<double> est_err_m;  // per estimate point, coloured with turbo; empty -> plain blue
  std::string unit = "m";
  std::string message;
};
void renderPlanTrajectory(const PlanTrajectory& p, const std::string& path, FigureSize size = {});

// ---- Comparisons (the paper's Fig. 6) -------------------------------------------------------------
struct CompareRun {
  std::string config;      // row label
  std::string sequence;    // column group label
  int run = 0;             // column inside the group (0-based)
  bool failed = false;     // drawn white with a cross
  double ate_m = kNaN;     // NaN and not failed: "no ground truth" (grey)
  std::string run_dir;     // the run's folder (index pages link to it)
  std::string error;       // why it failed
};

struct CompareGrid {
  std::string title = "ATE per run (log colour scale)";
  std::vector<std::string> configs;    // rows, top to bottom
  std::vector<std::string> sequences;  // column groups, left to right
  int runs = 1;                        // columns per sequence
  std::vector<CompareRun> cells;
  double lo_m = kNaN, hi_m = kNaN;     // colour scale limits; chosen from the data when NaN
};

// Rows/columns in order of first appearance; runs = 1 + the largest run index.
CompareGrid makeCompareGrid(const std::vector<CompareRun>& runs);
// One square per run: rows = configs, columns = sequences x runs; colour = ATE on a log scale
// (values beyond the scale saturate, as in the paper); failed = white with a cross; colour bar right.
// size {0, 0}: the figure is sized to the grid (squares of 16..48 px, readable labels).
void renderCompareGrid(const CompareGrid& g, const std::string& path, FigureSize size = {});
// Box plot of ATE per configuration over all its runs (log axis when the values span > 1 decade), every
// run as a dot, failed runs counted under each box.
void renderAtePerConfig(const CompareGrid& g, const std::string& path, FigureSize size = {});

// ---- Residual maps from a diagnostics log ---------------------------------------------------------
struct ResidualObservation {
  int64_t t_ns = 0;         // frame time (row y0)
  float x = 0, y = 0;       // pixel in the image the residual is evaluated in
  float row_minus_y0 = 0;   // raw (distorted) row minus y0: what the rolling shutter acts on
  float residual = 0;       // photometric residual (intensity units)
  float weight = 1;         // robust weight at the final linearisation
};

struct ResidualMapInput {
  int image_width = 0, image_height = 0;   // raw image size (rows = image_height)
  std::vector<ResidualObservation> obs;
  int time_bins = 60, row_bins = 48;       // row x time map
  int x_bins = 48;                         // image map (y bins follow the aspect ratio)
  bool weighted = false;                   // mean of weight*|r| instead of |r|
};
// Mean |residual| per (time, raw row) bin: rows down the y axis as in the image, time along x.
void renderResidualRowTime(const ResidualMapInput& in, const std::string& path, FigureSize size = {});
// Mean |residual| per image cell.
void renderResidualImage(const ResidualMapInput& in, const std::string& path, FigureSize size = {});

}  // namespace rsvio::viz
