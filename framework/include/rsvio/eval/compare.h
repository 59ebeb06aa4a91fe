// The comparison grid behind `rsvio compare`: every (config, dataset, run) is one child process
// (normally `rsvio run --config C --data D --out DIR/runs/<cfg>/<ds>/<k> --seed <k>`), run by the
// bounded pool of eval/process_pool.h, then read back and summarised.
//
// Contract:
// - Runs vary the estimator's seed (k = 0 .. runs-1); the dataset stays the same (conventions.md).
// - Each run's folder is emptied before it starts and holds the child's log.txt (stdout + stderr).
// - A run is ok when the child exits 0 and its report.json says "status": "ok". Otherwise it is failed
//   and `error` keeps why: the report's error, else how the child ended (exit code, signal, timeout)
//   with the last line of its log.
// - ATE of an ok run: report.json's eval.ate_rmse_m (and eval.align); when the report has none but the
//   dataset has ground truth, keyframes.tum (else trajectory.tum) is evaluated here with
//   eval/evaluate_files.h and the default alignment for its frame (as the paper's eq. 35: keyframes).
// - Summary per (config, dataset): runs, failed, median and mean ATE over ok runs with an ATE, median
//   and mean fps over ok runs. Failed runs never enter the ATE statistics; they are counted.
// - Interrupt (CompareOptions::stop_level, set by `rsvio compare` from SIGINT/SIGTERM): running children
//   get SIGTERM (an `rsvio run` stops at its next frame, writes its outputs, exits 130), no more start;
//   their records say "interrupted" / "not run" and stay out of the summary, which covers the finished
//   runs. A second signal kills the children (SIGKILL).
// - Resume (CompareOptions::resume): each run folder holds job.json (config hash, dataset, seed, --set
//   values), written before its child starts. A run whose job.json matches its job and whose report.json
//   says "ok" or "failed" is kept as it is; every other run folder is emptied and the run is started
//   again. The config hash is over the effective config (extends and --set applied).
// - The child command is injectable (RunArgvBuilder), so the scheduler and the aggregation are tested
//   with fake children.
#pragma once
#include <functional>
#include <iosfwd>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "rsvio/eval/process_pool.h"

namespace rsvio::eval {

struct CompareJob {
  std::string config_path, config_name;    // name: file stem, made unique and path-safe
  std::string dataset_dir, dataset_name;   // name: folder name, made unique and path-safe
  int run = 0;                             // also the seed
  std::string out_dir;                     // <out>/runs/<config_name>/<dataset_name>/<run>
  std::vector<std::string> sets;           // --set values given to every run
  std::string config_hash;                 // FNV-1a 64 of the effective config (hex); of the file's bytes
                                           // when it does not load
};

// Order: config, then dataset, then run.
std::vector<CompareJob> planCompareJobs(const std::vector<std::string>& configs, const std::vector<std::string>& datasets,
                                        int runs, const std::string& out_root,
                                        const std::vector<std::string>& sets = {});

// job.json of a run folder: what identifies the run for --resume.
nlohmann::json jobIdentity(const CompareJob& job);

using RunArgvBuilder = std::function<std::vector<std::string>(const CompareJob&)>;

// [program, pre_args..., "run", "--config", C, "--data", D, "--out", O, "--seed", k, ("--set", s)...]
std::vector<std::string> rsvioRunArgv(const std::string& program, const std::vector<std::string>& pre_args,
                                      const CompareJob& job);

struct RunRecord {
  CompareJob job;
  bool ok = false;
  std::string status = "failed";     // "ok", "failed", "interrupted" (stopped part way), "not run"
  bool kept = false;                 // --resume: the finished run of an earlier invocation
  std::string error;                 // empty when ok
  std::string eval_note;             // where the ATE came from, or why there is none
  std::optional<double> ate_rmse_m;
  std::string align;                 // alignment of that ATE
  std::optional<double> fps, realtime_factor;
  double wall_s = 0;
  std::string log_path;
};

// Reads the run's folder after its child ended (never throws: problems become the record's error).
RunRecord collectRun(const CompareJob& job, const ChildOutcome& outcome);

struct GroupSummary {
  std::string config_name, dataset_name;
  size_t runs = 0, failed = 0, with_ate = 0;
  std::optional<double> ate_median_m, ate_mean_m, fps_median, fps_mean;
};

struct CompareOptions {
  int jobs = 2;
  double timeout_s = 3600;
  bool resume = false;
  std::function<int()> stop_level;   // see process_pool.h: 0 run on, 1 stop, 2 kill
};

struct CompareResult {
  std::vector<RunRecord> runs;       // in job order
  std::vector<GroupSummary> groups;  // finished runs only, in (config, dataset) order of first appearance
  bool interrupted = false;          // stop_level was raised: some runs are "interrupted" or "not run"
  size_t failed() const;             // status "failed"
  size_t unfinished() const;         // status "interrupted" or "not run"
  size_t kept() const;               // kept from an earlier invocation (--resume)
};

std::vector<GroupSummary> summariseRuns(const std::vector<RunRecord>& runs);

// Runs the grid; prints one progress line per finished run to `progress` (may be null), e.g.
// "[12/30] gs_vo on seq01 run 3: ok ATE 0.023 m 12.3 fps".
CompareResult runCompare(const std::vector<CompareJob>& jobs, const RunArgvBuilder& argv_builder,
                         const CompareOptions& options, std::ostream* progress);

std::string formatCompareTable(const CompareResult& r);
nlohmann::json compareToJson(const CompareResult& r);
// <out>/compare.csv (one "summary" row per config and dataset, then one "run" row per run) and
// <out>/compare.json ({"summary": [...], "runs": [...]}, plus "invocation" when given: what to pass
// to `rsvio compare` to run the same grid again).
void writeCompareOutputs(const std::string& out_dir, const CompareResult& r,
                         const nlohmann::json& invocation = nlohmann::json());

}  // namespace rsvio::eval
