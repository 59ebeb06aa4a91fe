// Snapshot: an immutable picture of one finished (or failed) run, built only from the files the run
// wrote (user-contract.md, "Files a run writes") plus the ground truth of the dataset it names. It is
// what viz/ renders and what anything else that looks at a run after the fact should consume; it never
// touches estimator internals, so a figure can be drawn for a run of any version, or a run that failed.
//
// Contract:
// - Frames: `trajectory` and `keyframes` are T_W_X poses as written (X = body or camera, from the
//   "# frame:" header). `ground_truth` is in the same frame X as the estimate (EuRoC body poses are
//   mapped to the camera through T_BS of <dataset>/mav0/cam0/sensor.yaml for camera-frame runs) and
//   in the ground truth's own world.
// - Errors: `errors->alignment` maps estimate-world points into the ground-truth world
//   (p_gt ~ s R p_est + t), computed on keyframes as report.json's ATE is (the paper's eq. 35), with
//   the report's "align" when it gives one, otherwise Sim(3) for camera-frame runs and SE(3) for
//   body-frame runs (eval::defaultAlignFor). Every frame of trajectory.tum is then given its position
//   error under that one alignment (nearest ground-truth stamp within max_dt_ns).
// - Reading never throws for a missing or malformed optional file: the reason is recorded in `notes`
//   and the member stays empty, so a failed run still yields a snapshot. Only a missing run folder throws
//   (DataError).
// - Time: int64 ns, as everywhere.
#pragma once
#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "rsvio/eval/alignment.h"
#include "rsvio/eval/trajectory_metrics.h"
#include "rsvio/io/ply.h"
#include "rsvio/io/states.h"
#include "rsvio/io/trajectory.h"

namespace rsvio::io {

// The fields of report.json a viewer needs, read leniently (absent -> NaN / -1 / empty).
struct RunSummary {
  static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  std::string status = "unknown";  // "ok", "failed", or "unknown" when report.json is missing
  std::string error;               // report.json "error" for failed runs
  long frames = -1;
  long keyframes = -1;
  double fps = kNaN;
  double realtime_factor = kNaN;
  double scale = kNaN;
  std::vector<std::pair<std::string, double>> stage_ms;  // by stage name (JSON objects are read sorted)
  std::string dataset;        // report.json "dataset" as written
  double ate_rmse_m = kNaN;   // report.json eval.ate_rmse_m
  std::string align;          // report.json eval.align
};

RunSummary parseRunSummary(const nlohmann::json& report);

// Position error of one estimated pose after alignment.
struct PoseError {
  int64_t t_ns = 0;
  Eigen::Vector3d p_est_aligned = Eigen::Vector3d::Zero();  // ground-truth world
  Eigen::Vector3d p_gt = Eigen::Vector3d::Zero();
  double err_m = 0;
};

struct SnapshotErrors {
  eval::Alignment alignment;       // estimate world -> ground-truth world
  std::string aligned_on;          // "keyframes" or "trajectory" (when keyframes are too few)
  std::string align_reason;        // e.g. "report.json eval.align", "default for camera poses"
  eval::ErrorStats ate_m;          // on the poses the alignment was computed from
  std::vector<PoseError> frames;   // every associated pose of trajectory.tum (or keyframes.tum)
};

struct Snapshot {
  std::string run_dir;
  std::string name;                // the run folder's name, for titles
  nlohmann::json report = nlohmann::json::object();
  RunSummary summary;
  Trajectory trajectory;           // trajectory.tum
  Trajectory keyframes;            // keyframes.tum
  PointCloud points;               // points.ply
  std::vector<StateRow> states;    // states.csv
  std::string diagnostics_path;    // diagnostics.bin when present (read on demand: it can be large)
  Trajectory ground_truth;         // same pose frame as the estimate, ground-truth world
  std::string ground_truth_source;
  std::optional<Eigen::Isometry3d> T_B_C;  // camera -> body from the dataset's sensor.yaml, when found
  std::optional<SnapshotErrors> errors;    // when ground truth and enough associated poses exist
  std::vector<std::string> notes;          // what could not be read or computed, and why

  bool failed() const { return summary.status == "failed"; }
  // The frame of the estimate (trajectory's header, else keyframes').
  PoseFrame poseFrame() const { return trajectory.frame != PoseFrame::kUnknown ? trajectory.frame : keyframes.frame; }
};

struct SnapshotOptions {
  std::string ground_truth_path;  // overrides the dataset named in report.json
  std::string dataset_dir;        // overrides report.json "dataset"
  int64_t max_dt_ns = 10'000'000; // association tolerance (eval's default)
};

// Reads <run_dir>/{report.json, trajectory.tum, keyframes.tum, points.ply, states.csv} and the ground
// truth, and notes where diagnostics.bin is. Throws DataError only when run_dir is not a folder.
Snapshot readSnapshot(const std::string& run_dir, const SnapshotOptions& options = {});

// The error part alone, for snapshots assembled in memory (tests, a run that has its data at hand).
// Returns nullopt and appends to notes when the errors cannot be computed.
std::optional<SnapshotErrors> computeSnapshotErrors(const Trajectory& trajectory, const Trajectory& keyframes,
                                                    const Trajectory& ground_truth, const std::string& report_align,
                                                    int64_t max_dt_ns, std::vector<std::string>& notes);

}  // namespace rsvio::io
