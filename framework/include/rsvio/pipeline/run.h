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
  Report report;
  nlohmann::json effective_config;
  std::string out_dir;
};

// Loads, validates (ConfigError listing every problem) and returns the effective config of a run.
nlohmann::json loadRunConfig(const std::string& path, const std::vector<std::string>& sets, PluginHost& host);

// Runs and writes the outputs. Throws ConfigError/DataError/Error for problems found before the dataset
// is open (bad config, unreadable dataset); later failures (divergence, a missing image mid-sequence)
// end in report.status == "failed" with the reason, and are returned, not thrown.
RunResult runPipeline(const RunRequest& request, PluginHost& host);

}  // namespace rsvio
