// rsvio eval: compare an estimated TUM trajectory with ground truth (ATE, RPE, error over time).
// Everything but the printing lives in the framework (rsvio/eval/evaluate_files.h); docs/eval.md
// explains the metrics, the association rule and the alignment.
#include <filesystem>
#include <fstream>
#include <iostream>

#include "commands.h"
#include "rsvio/core/error.h"
#include "rsvio/core/time.h"
#include "rsvio/eval/evaluate_files.h"

namespace rsvio::app {
namespace {

struct EvalArgs {
  std::string data, gt, est, calib, align, out;
  bool json = false;
  double max_dt_s = 0.01;
  std::vector<double> rpe_fractions{0.01, 0.02, 0.05, 0.10};
  std::vector<double> rpe_distances_m;
  std::vector<double> rpe_windows_s{0.5, 1.0, 2.0, 5.0};
};

int runEval(const EvalArgs& a) {
  if (a.data.empty() == a.gt.empty()) throw ConfigError("rsvio eval: give exactly one of --data DIR or --gt FILE");
  if (!(a.max_dt_s > 0)) throw ConfigError("--max-dt = " + std::to_string(a.max_dt_s) + ". Violated constraint: > 0");
  for (double v : a.rpe_fractions)
    if (!(v > 0 && v <= 1)) throw ConfigError("--rpe-fractions: " + std::to_string(v) + " is not in (0, 1]");
  eval::FileEvalRequest req;
  req.dataset_dir = a.data;
  req.gt_path = a.gt;
  req.est_path = a.est;
  req.calib_path = a.calib;
  if (!a.align.empty()) req.align = eval::parseAlignMode(a.align);
  req.options.max_dt_ns = sToNs(a.max_dt_s);
  req.options.rpe_path_fractions = a.rpe_fractions;
  req.options.rpe_distances_m = a.rpe_distances_m;
  req.options.rpe_windows_s = a.rpe_windows_s;
  const auto outcome = eval::evaluateFiles(req);
  const auto j = eval::evalToJson(outcome.result, outcome.context);
  if (a.json) {
    std::cout << j.dump(2) << "\n";
  } else {
    std::cout << eval::formatEvalTable(outcome.result, outcome.context);
  }
  if (!a.out.empty()) {
    namespace fs = std::filesystem;
    std::error_code ec;
    fs::create_directories(a.out, ec);
    if (ec) throw Error(a.out + ": cannot create folder (" + ec.message() + ")");
    const std::string json_path = (fs::path(a.out) / "eval.json").string();
    std::ofstream f(json_path);
    if (!(f << j.dump(2) << "\n")) throw Error(json_path + ": write failed");
    eval::writeErrorOverTimeCsv((fs::path(a.out) / "error_over_time.csv").string(), outcome.result);
  }
  return 0;
}

}  // namespace

void addEvalCommand(CLI::App& root, const GlobalOptions& /*g*/, CommandResult& r) {
  auto args = std::make_shared<EvalArgs>();
  auto* sub = root.add_subcommand("eval", "compare an estimated trajectory with ground truth (ATE, RPE)");
  auto* data = sub->add_option("--data", args->data, "dataset folder (EuRoC layout) whose ground truth to use");
  auto* gt = sub->add_option("--gt", args->gt, "ground-truth file: EuRoC csv or TUM");
  data->excludes(gt);
  sub->add_option("--est", args->est, "estimated trajectory (TUM, optional '# frame: body|camera' header)")->required();
  sub->add_option("--align", args->align,
                  "se3 | sim3 | none (default: sim3 for '# frame: camera', se3 otherwise)");
  sub->add_flag("--json", args->json, "print JSON instead of the table");
  sub->add_option("--max-dt", args->max_dt_s, "largest |t_gt - t_est| of an associated pair, seconds")
      ->capture_default_str();
  sub->add_option("--out", args->out, "folder to write eval.json and error_over_time.csv into");
  sub->add_option("--calib", args->calib,
                  "sensor.yaml with T_BS for camera-frame estimates (default <data>/mav0/cam0/sensor.yaml)");
  sub->add_option("--rpe-fractions", args->rpe_fractions, "RPE distances as fractions of the path length")
      ->delimiter(',')
      ->capture_default_str();
  sub->add_option("--rpe-distances-m", args->rpe_distances_m, "RPE distances in metres (in addition)")->delimiter(',');
  sub->add_option("--rpe-windows-s", args->rpe_windows_s, "RPE time windows in seconds")
      ->delimiter(',')
      ->capture_default_str();
  sub->callback([args, &r] { r.exit_code = runEval(*args); });
}

}  // namespace rsvio::app
