// rsvio compare: run every (config, dataset, run) as a child `rsvio run` in a bounded pool of worker
// processes and tabulate ATE, failures and fps (framework: rsvio/eval/compare.h; docs/eval.md).
// Exit code: 0 when every run is ok, 1 when at least one failed (the table and files are still
// written), 2 for a usage or setup error (missing config or dataset, unwritable --out), 130 when stopped
// by SIGINT/SIGTERM: the running children get SIGTERM (they stop at their next frame and keep their
// outputs), the table of the runs finished so far is written, and `--resume` finishes the grid later
// (finished runs are kept, matched by config hash, dataset and seed). A second signal kills the children.
#include <signal.h>

#include <csignal>
#include <filesystem>
#include <iostream>
#include <memory>

#include "commands.h"
#include "rsvio/config/config.h"
#include "rsvio/core/error.h"
#include "rsvio/eval/compare.h"
#include "rsvio/pipeline/run.h"
#ifdef RSVIO_HAVE_VIZ
#include "rsvio/viz/render_run.h"
#endif

namespace rsvio::app {
namespace {

volatile std::sig_atomic_t g_compare_signals = 0;

extern "C" void onCompareSignal(int) {
  if (g_compare_signals < 2) g_compare_signals = g_compare_signals + 1;
}

void installCompareSignalHandlers() { installInterruptHandler(onCompareSignal); }

struct CompareArgs {
  std::vector<std::string> configs, datasets, sets;
  bool resume = false;
  int runs = 1;
  int jobs = 2;
  double timeout_s = 3600;
  std::string out;
  std::string runner;  // hidden: a program used instead of this binary (tests, scripts)
  bool no_figures = false;
};

// The grid figure and page (viz, when built): never throws, a problem is one line on stderr.
void renderFigures(const CompareArgs& a, const eval::CompareResult& result, int verbosity) {
#ifdef RSVIO_HAVE_VIZ
  std::vector<viz::CompareRun> runs;
  for (const auto& x : result.runs) {
    if (x.status == "interrupted" || x.status == "not run") continue;
    viz::CompareRun c;
    c.config = x.job.config_name;
    c.sequence = x.job.dataset_name;
    c.run = x.job.run;
    c.failed = !x.ok;
    if (x.ate_rmse_m) c.ate_m = *x.ate_rmse_m;
    c.run_dir = x.job.out_dir;
    c.error = x.error;
    runs.push_back(c);
  }
  viz::CompareRenderOptions opt;
  opt.out_dir = a.out;
  opt.notes.push_back("ATE: report.json eval.ate_rmse_m, else keyframes.tum against the dataset's ground truth");
  const auto status = viz::renderCompare(runs, opt);
  if (!status.ok) std::cerr << "rsvio compare: figures: " << status.message << "\n";
  if (verbosity > 0 && !status.index_html.empty()) std::cout << "page: " << status.index_html << "\n";
#else
  (void)a;
  (void)result;
  (void)verbosity;
#endif
}

std::string thisBinary() {
  std::error_code ec;
  const auto p = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) throw Error("rsvio compare: cannot find its own binary through /proc/self/exe (" + ec.message() + ")");
  return p.string();
}

int runCompareCommand(const CompareArgs& a, const GlobalOptions& g) {
  namespace fs = std::filesystem;
  if (a.runs < 1) throw ConfigError("--runs = " + std::to_string(a.runs) + ". Violated constraint: >= 1");
  if (a.jobs < 1) throw ConfigError("--jobs = " + std::to_string(a.jobs) + ". Violated constraint: >= 1");
  for (const auto& c : a.configs) {
    if (!fs::is_regular_file(c)) throw ConfigError("--configs: " + c + ": no such file");
  }
  for (const auto& d : a.datasets) {
    if (!fs::is_directory(d)) throw ConfigError("--data: " + d + ": no such folder");
  }
  // A --set that cannot apply is the grid's usage error, not a failure of every run.
  if (!a.sets.empty())
    for (const auto& c : a.configs) (void)loadConfigWithSets(c, a.sets);
  const auto jobs = eval::planCompareJobs(a.configs, a.datasets, a.runs, a.out, a.sets);
  eval::RunArgvBuilder builder;
  if (!a.runner.empty()) {
    builder = [runner = a.runner](const eval::CompareJob& j) { return eval::rsvioRunArgv(runner, {}, j); };
  } else {
    std::vector<std::string> pre;  // pass the plugin search path on, one "--plugin-path=P" per folder
    for (const auto& p : g.plugin_path) pre.push_back("--plugin-path=" + p);
    builder = [bin = thisBinary(), pre](const eval::CompareJob& j) { return eval::rsvioRunArgv(bin, pre, j); };
  }
  eval::CompareOptions opt;
  opt.jobs = a.jobs;
  opt.timeout_s = a.timeout_s;
  opt.resume = a.resume;
  opt.stop_level = [] { return static_cast<int>(g_compare_signals); };
  installCompareSignalHandlers();
  if (g.verbosity > 0) {
    std::cout << "rsvio compare: " << jobs.size() << " runs (" << a.configs.size() << " configs x " << a.datasets.size()
              << " datasets x " << a.runs << " seeds), " << a.jobs << " at a time, into " << a.out << "/runs\n";
  }
  const auto result = eval::runCompare(jobs, builder, opt, g.verbosity > 0 ? &std::cout : nullptr);
  // Absolute paths, so the grid can be run again from anywhere (scripts/reproduce_compare.sh --from).
  auto absolute = [](const std::vector<std::string>& v) {
    std::vector<std::string> out;
    for (const auto& p : v) out.push_back(fs::absolute(p).lexically_normal().string());
    return out;
  };
  const nlohmann::json invocation = {{"configs", absolute(a.configs)}, {"data", absolute(a.datasets)},
                                     {"runs", a.runs}, {"jobs", a.jobs}, {"timeout_s", a.timeout_s},
                                     {"sets", a.sets}};
  eval::writeCompareOutputs(a.out, result, invocation);
  std::cout << "\n" << eval::formatCompareTable(result);
  std::cout << "written: " << (fs::path(a.out) / "compare.csv").string() << ", "
            << (fs::path(a.out) / "compare.json").string() << "\n";
  if (result.interrupted) {
    std::cerr << "rsvio compare: interrupted: " << result.unfinished()
              << " runs not finished; the same command with --resume finishes the grid\n";
    return 130;
  }
  if (!a.no_figures) renderFigures(a, result, g.verbosity);
  return result.failed() == 0 ? 0 : 1;
}

}  // namespace

void addCompareCommand(CLI::App& root, const GlobalOptions& g, CommandResult& r) {
  auto args = std::make_shared<CompareArgs>();
  auto* sub = root.add_subcommand("compare", "run configs x datasets x seeds in parallel and tabulate ATE, failures, fps");
  sub->add_option("--configs", args->configs, "config files (JSON)")->required();
  sub->add_option("--data", args->datasets, "dataset folders (EuRoC layout)")->required();
  sub->add_option("--set", args->sets, "override a config key in every config of the grid: a.b.c=value")->take_all();
  sub->add_flag("--resume", args->resume,
                "keep the finished runs of an earlier invocation into --out (same config, data, seed) and run the rest");
  sub->add_option("--runs", args->runs, "runs per (config, dataset); run k uses --seed k")->capture_default_str();
  sub->add_option("--jobs", args->jobs, "worker processes at once")->capture_default_str();
  sub->add_option("--timeout-s", args->timeout_s, "a run longer than this is killed and counted as failed (0: none)")
      ->capture_default_str();
  sub->add_option("--out", args->out, "output folder: runs/<config>/<dataset>/<k>/, compare.csv, compare.json")
      ->required();
  // Hidden (empty group): replaces `<this binary>` as the child program; it gets the same arguments
  // ("run --config C --data D --out O --seed k"). For tests and scripts with a stand-in runner.
  sub->add_option("--runner", args->runner, "program to run instead of this binary")->group("");
  sub->add_flag("--no-figures", args->no_figures, "skip the grid figures and index.html (drawn when viz is built)");
  sub->callback([args, &g, &r] { r.exit_code = runCompareCommand(*args, g); });
}

}  // namespace rsvio::app
