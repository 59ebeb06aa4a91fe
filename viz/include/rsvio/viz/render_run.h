// Everything a run or a comparison leaves to look at: figures (PNG) and an index.html that shows them
// beside the run's tables. The entry points for `rsvio render`, the end of `rsvio run` and `rsvio compare`.
//
// Contract:
// - Never throws and never exits: a failed render is reported in RenderStatus (ok = false, a one-line
//   message, one line per problem) and the caller logs it and carries on; the run's own outputs are
//   never touched (only the figure folder and the index page are written).
// - What needs no display (2D figures, the index page) is written even when 3D rendering is impossible
//   (no X display and no Xvfb): the page then says why the 3D views are missing.
// - Files of a run (defaults): <run>/figures/*.png and <run>/index.html, links relative so the folder
//   can be moved or served as is.
//   figures: trajectory_{top,side,perspective,overview}.png (VTK), trajectory_plan.png, error_over_time.png,
//   states.png, residual_row_time.png and residual_image.png (when diagnostics.bin is there).
// - Files of a comparison: <out>/figures/compare_grid.png, ate_per_config.png, <out>/index.html.
#pragma once
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "rsvio/io/diagnostics_log.h"
#include "rsvio/io/snapshot.h"
#include "rsvio/viz/display_guard.h"
#include "rsvio/viz/figures.h"
#include "rsvio/viz/scene.h"

namespace rsvio::viz {

struct RenderStatus {
  bool ok = false;                    // every asked figure and the index page written
  std::string message;                // one line for the log
  std::vector<std::string> figures;   // written PNGs
  std::string index_html;             // written page ("" when it could not be written)
  std::vector<std::string> problems;  // one line each
};

struct RenderOptions {
  std::string out_dir;        // default <run>/figures
  std::string index_path;     // default <run>/index.html
  FigureSize figure{960, 540};
  SceneOptions scene;         // 3D view size and content
  bool scenes = true;         // false: 2D figures only (no display needed)
  DisplayGuardOptions display;
  // Residuals to map; default: read from the snapshot's diagnostics.bin when present.
  std::optional<ResidualMapInput> residuals;
};

RenderStatus renderRun(const io::Snapshot& snapshot, const RenderOptions& options = {});
// Reads the snapshot first (a missing folder is reported in the status, not thrown).
RenderStatus renderRunFolder(const std::string& run_dir, const RenderOptions& options = {});

// The panels of states.png: only what the run estimated. A quantity that is exactly zero in every row of
// states.csv was not estimated (a visual-odometry run has no velocity or biases; a global shutter may
// have no twist) and gets no panel: its title goes to *not_estimated instead. Scale gets a panel only
// when has_scale (report.json has a scale, as the run page shows it; visual odometry has none).
// dynamic_marginalization: report.json extra.vio.dynamic_marginalization when the run had it; the scale
// panel then also draws the interval [centre / d, centre * d] over time, so its switches show.
std::vector<Panel> keyframeStatePanels(const std::vector<StateRow>& rows, bool has_scale,
                                       std::vector<std::string>* not_estimated = nullptr,
                                       const nlohmann::json* dynamic_marginalization = nullptr);

// Mean-residual maps' input from a diagnostics log (every observation; weights kept).
ResidualMapInput residualMapInput(const DiagnosticsLog& log);

// ---- Comparisons ---------------------------------------------------------------------------------
struct FigureLink {
  std::string path;     // file on disk
  std::string caption;
  bool wide = false;    // spans the page's width (wide figures such as the compare grid)
};

struct CompareRenderOptions {
  std::string out_dir;         // the comparison folder (index.html goes here)
  std::string figures_dir;     // default <out_dir>/figures
  std::string title = "rsvio comparison";
  FigureSize figure{960, 540};
  double lo_m = kNaN, hi_m = kNaN;  // compare grid colour scale (auto when NaN)
  std::vector<std::string> notes;   // shown on the page (e.g. the command line)
};

// Draws compare_grid.png and ate_per_config.png and writes <out_dir>/index.html.
RenderStatus renderCompare(const std::vector<CompareRun>& runs, const CompareRenderOptions& options);

// The comparison page alone: a table per configuration (runs, failed, median/mean ATE), every run with
// a link to its own index.html (or folder), the figures and the notes. Throws rsvio::Error when the page
// cannot be written.
void writeCompareIndex(const std::string& index_path, const std::string& title, const std::vector<CompareRun>& runs,
                       const std::vector<FigureLink>& figures, const std::vector<std::string>& notes = {});

// The run page alone (renderRun calls it). Throws rsvio::Error when the page cannot be written.
void writeRunIndex(const std::string& index_path, const io::Snapshot& snapshot, const std::vector<FigureLink>& figures,
                   const std::vector<std::string>& problems);

}  // namespace rsvio::viz
