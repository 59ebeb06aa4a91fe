// rsvio render --run DIR [--out DIR]: figures of a finished (or failed) run and its index.html.
// Everything but the arguments lives in viz/ (rsvio/viz/render_run.h); docs/figures.md says what each
// figure shows. Without --out: <run>/figures/*.png and <run>/index.html. With --out X: X/*.png and
// X/index.html, and the run folder is not touched (its own page keeps pointing at its own figures).
// Exit 0 when every figure was written; 1 with a one-line message when some could not be (the others
// and the page are still written); 2 when the run folder does not exist or holds nothing to draw (no
// report.json, trajectory, keyframes, points or states: not a run folder), and nothing is written.
#include <filesystem>
#include <iostream>
#include <memory>

#include "commands.h"
#include "rsvio/core/error.h"
#ifdef RSVIO_HAVE_VIZ
#include "rsvio/io/snapshot.h"
#include "rsvio/viz/render_run.h"
#endif

namespace rsvio::app {

#ifdef RSVIO_HAVE_VIZ
namespace {

struct RenderArgs {
  std::string run, out, data, gt;
  int width = 1280, height = 960;
  bool no_3d = false;
};

int runRender(const RenderArgs& a, int verbosity) {
  if (a.width < 16 || a.height < 16) throw ConfigError("--size: figures must be at least 16x16 pixels");
  io::SnapshotOptions so;
  so.dataset_dir = a.data;
  so.ground_truth_path = a.gt;
  const io::Snapshot snap = io::readSnapshot(a.run, so);  // DataError when the folder is missing
  if (!snap.report.contains("status") && snap.trajectory.empty() && snap.keyframes.empty() && snap.points.size() == 0 &&
      snap.states.empty())
    throw DataError(a.run + ": nothing to draw: no report.json, trajectory.tum, keyframes.tum, points.ply or "
                            "states.csv (is this a folder written by rsvio run?)");
  // A folder that cannot be made (under a file, read-only) is bad input: said before drawing anything.
  const std::filesystem::path fig_dir = a.out.empty() ? std::filesystem::path(a.run) / "figures" : std::filesystem::path(a.out);
  std::error_code ec;
  std::filesystem::create_directories(fig_dir, ec);
  if (ec) throw Error(fig_dir.string() + ": cannot create the figure folder (" + ec.message() + ")");
  viz::RenderOptions o;
  o.out_dir = a.out;
  if (!a.out.empty()) o.index_path = (std::filesystem::path(a.out) / "index.html").string();
  o.scene.width = a.width;
  o.scene.height = a.height;
  o.scenes = !a.no_3d;
  const viz::RenderStatus st = viz::renderRun(snap, o);
  if (verbosity >= 2) {
    for (const auto& n : snap.notes) std::cerr << "note: " << n << "\n";
  }
  if (verbosity >= 1) {
    for (const auto& f : st.figures) std::cout << f << "\n";
    if (!st.index_html.empty()) std::cout << st.index_html << "\n";
  }
  if (!st.ok) {
    std::cerr << "rsvio render: " << st.message << "\n";
    return 1;
  }
  return 0;
}

}  // namespace
#endif

void addRenderCommand(CLI::App& root, const GlobalOptions& g, CommandResult& r) {
#ifdef RSVIO_HAVE_VIZ
  auto args = std::make_shared<RenderArgs>();
  auto* sub = root.add_subcommand("render", "figures and index.html of a run folder (off-screen, no window)");
  sub->add_option("--run", args->run, "run folder written by rsvio run")->required()->check(NonEmpty("run folder"));
  sub->add_option("--out", args->out,
                  "write the figures and index.html into this folder instead (the run folder is left untouched); "
                  "default: <run>/figures and <run>/index.html")
      ->check(NonEmpty("output folder"));
  sub->add_option("--data", args->data, "dataset folder for ground truth (default: report.json's \"dataset\")");
  sub->add_option("--gt", args->gt, "ground-truth file (EuRoC csv or TUM), instead of the dataset's");
  sub->add_option("--width", args->width, "3D view width in pixels")->capture_default_str();
  sub->add_option("--height", args->height, "3D view height in pixels")->capture_default_str();
  sub->add_flag("--no-3d", args->no_3d, "2D figures only (no X display or Xvfb needed)");
  sub->callback([args, &g, &r] { r.exit_code = runRender(*args, g.verbosity); });
#else
  (void)g;
  auto* sub = root.add_subcommand("render", "(not available: built without viz, -DRSVIO_BUILD_VIZ=OFF)");
  sub->allow_extras();
  sub->callback([&r] { r.exit_code = notAvailableYet("render", "this build has no viz library (RSVIO_BUILD_VIZ=OFF)"); });
#endif
}

}  // namespace rsvio::app
