// One run of the estimator on a dataset, as `rsvio run` and `rsvio demo` do it: load and validate the
// config, open the data source, feed IMU and frames to rsvio::Odometry with progress output, write the
// run's files (user-contract.md, "Files a run writes"), evaluate against the dataset's ground truth when
// it has one (evaluation only: the estimator never sees it).
//
// Files in out_dir: config.json (effective config), trajectory.tum, keyframes.tum, points.ply, states.csv,
// diagnostics.bin, report.json. report.json is written in every case that gets as far as opening the
// dataset, with status "failed" and the error when the run fails; what was estimated before the failure
// is still written.
//
// Interrupts (user-contract.md, exit code 130): after installRunInterruptHandlers(), the first SIGINT or
// SIGTERM asks the run to stop at the next frame: the frame loop ends, everything estimated so far is
// written as after a normal end and report.json says status "interrupted" with the signal in "error".
// A second signal of either kind ends the process at once (default action). Every output file is
// written atomically (io/atomic_file.h) and report.json last, so even SIGKILL at any moment never leaves
// a report.json beside truncated files; a report.json saying "ok" means every file beside it is complete.
//
// Clean folder: a run removes the files an earlier run left in out_dir (the contract files above,
// render outputs index.html and figures/, stale temporaries) before writing anything, report.json
// first, so no stale file outlives its run. Other files in out_dir are left alone.
//
// IMU feeding: before frame f (stamp t_f, camera clock) the odometry receives every IMU sample with
// t_imu <= t_f + time_offset + half a frame period, so a rolling-shutter frame's whole readout is covered.
#pragma once
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "rsvio/io/report.h"

namespace rsvio {

class PluginHost;

struct RunRequest {
  std::string config_path;
  std::vector<std::string> sets;   // --set a.b=value
  std::string data_dir;
  std::string out_dir;
  long seed = -1;                  // -1: the config's seed
  int verbosity = 1;               // 0 quiet, 1 progress every ~2 s, 2 every frame
};

struct RunResult {
  Report report;                   // status "ok", "failed" or "interrupted"
  nlohmann::json effective_config;
  std::string out_dir;
};

// Loads, validates (ConfigError listing every problem) and returns the effective config of a run.
nlohmann::json loadRunConfig(const std::string& path, const std::vector<std::string>& sets, PluginHost& host);

// Runs and writes the outputs. Throws ConfigError/DataError/Error for problems found before the dataset
// is open (bad config, unreadable dataset); later failures (divergence, a missing image mid-sequence)
// end in report.status == "failed" with the reason, and are returned, not thrown.
RunResult runPipeline(const RunRequest& request, PluginHost& host);

// SIGINT/SIGTERM handlers for the process (see "Interrupts" above); `rsvio run` installs them.
void installRunInterruptHandlers();
// Installs `handler` for SIGINT and SIGTERM (SA_RESTART); the run's handlers and rsvio compare's use it.
void installInterruptHandler(void (*handler)(int));
// The signal that asked the run to stop (0: none yet).
int runInterruptSignal();
// Asks a run in progress (or the next one) to stop as a signal would; sig = 0 clears the request.
void requestRunInterrupt(int sig);

// The files a run writes into its folder (and removes there before it starts).
const std::vector<std::string>& runOutputFiles();

}  // namespace rsvio
