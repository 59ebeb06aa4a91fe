// Snapshot of a run folder (rsvio/io/snapshot.h).
#include "rsvio/io/snapshot.h"

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "rsvio/core/error.h"
#include "rsvio/eval/association.h"
#include "rsvio/eval/eval_output.h"
#include "rsvio/eval/extrinsic.h"

namespace rsvio::io {
namespace fs = std::filesystem;

namespace {

double jsonNumber(const nlohmann::json& j, const char* key) {
  if (!j.is_object()) return RunSummary::kNaN;
  const auto it = j.find(key);
  return (it != j.end() && it->is_number()) ? it->get<double>() : RunSummary::kNaN;
}

std::string jsonString(const nlohmann::json& j, const char* key) {
  if (!j.is_object()) return "";
  const auto it = j.find(key);
  return (it != j.end() && it->is_string()) ? it->get<std::string>() : "";
}

// Reads one optional file; a failure becomes a note, never an exception.
template <class F>
void readOptional(const fs::path& p, std::vector<std::string>& notes, F&& read) {
  if (!fs::exists(p)) {
    notes.push_back(p.filename().string() + ": not present");
    return;
  }
  try {
    read(p.string());
  } catch (const std::exception& e) {
    notes.push_back(e.what());
  }
}

}  // namespace

RunSummary parseRunSummary(const nlohmann::json& r) {
  RunSummary s;
  if (!r.is_object()) return s;
  const std::string status = jsonString(r, "status");
  if (!status.empty()) s.status = status;
  s.error = jsonString(r, "error");
  const double frames = jsonNumber(r, "frames");
  const double keyframes = jsonNumber(r, "keyframes");
  if (std::isfinite(frames)) s.frames = static_cast<long>(frames);
  if (std::isfinite(keyframes)) s.keyframes = static_cast<long>(keyframes);
  s.fps = jsonNumber(r, "fps");
  s.realtime_factor = jsonNumber(r, "realtime_factor");
  s.scale = jsonNumber(r, "scale");
  s.dataset = jsonString(r, "dataset");
  const auto st = r.find("stage_ms");
  if (st != r.end() && st->is_object()) {
    for (const auto& [k, v] : st->items()) {
      if (v.is_number()) s.stage_ms.emplace_back(k, v.get<double>());
    }
  }
  const auto ev = r.find("eval");
  if (ev != r.end() && ev->is_object()) {
    s.ate_rmse_m = jsonNumber(*ev, "ate_rmse_m");
    s.align = jsonString(*ev, "align");
  }
  return s;
}

std::optional<SnapshotErrors> computeSnapshotErrors(const Trajectory& trajectory, const Trajectory& keyframes,
                                                    const Trajectory& ground_truth, const std::string& report_align,
                                                    int64_t max_dt_ns, std::vector<std::string>& notes) {
  if (ground_truth.empty()) return std::nullopt;
  if (trajectory.empty() && keyframes.empty()) return std::nullopt;
  const PoseFrame frame = trajectory.frame != PoseFrame::kUnknown ? trajectory.frame : keyframes.frame;

  eval::EvalOptions opt;
  opt.max_dt_ns = max_dt_ns;
  opt.rpe_path_fractions.clear();
  opt.rpe_windows_s.clear();
  SnapshotErrors out;
  if (!report_align.empty()) {
    try {
      opt.align = eval::parseAlignMode(report_align, "report.json eval.align");
      out.align_reason = "report.json eval.align";
    } catch (const std::exception& e) {
      notes.push_back(e.what());
      opt.align = eval::defaultAlignFor(frame);
    }
  } else {
    opt.align = eval::defaultAlignFor(frame);
    out.align_reason = frame == PoseFrame::kCamera ? "default for camera poses (no metric scale)"
                                                   : "default for metric poses";
  }

  // Keyframes first (the paper's eq. 35); the frame trajectory when keyframes cannot be aligned.
  std::optional<eval::EvalResult> res;
  std::string first_error;
  for (const auto* est : {&keyframes, &trajectory}) {
    if (est->empty()) continue;
    try {
      res = eval::evaluateTrajectory(ground_truth, *est, opt);
      out.aligned_on = est == &keyframes ? "keyframes" : "trajectory";
      break;
    } catch (const std::exception& e) {
      if (first_error.empty()) first_error = e.what();
    }
  }
  if (!res) {
    notes.push_back("errors not computed: " + first_error);
    return std::nullopt;
  }
  out.alignment = res->alignment;
  out.ate_m = res->ate_m;

  const Trajectory& dense = trajectory.empty() ? keyframes : trajectory;
  const eval::Association assoc = eval::associateNearest(dense, ground_truth, max_dt_ns);
  out.frames.reserve(assoc.pairs.size());
  for (const auto& pr : assoc.pairs) {
    PoseError e;
    e.t_ns = dense.poses[pr.i_est].t_ns;
    e.p_est_aligned = out.alignment.apply(dense.poses[pr.i_est].p_W_X);
    e.p_gt = ground_truth.poses[pr.i_gt].p_W_X;
    e.err_m = (e.p_gt - e.p_est_aligned).norm();
    out.frames.push_back(e);
  }
  return out;
}

Snapshot readSnapshot(const std::string& run_dir, const SnapshotOptions& options) {
  const fs::path dir(run_dir);
  if (!fs::is_directory(dir)) throw DataError::at(run_dir, 0, "run folder does not exist");
  Snapshot s;
  s.run_dir = run_dir;
  s.name = fs::absolute(dir).lexically_normal().filename().string();
  if (s.name.empty()) s.name = fs::absolute(dir).lexically_normal().parent_path().filename().string();
  auto& notes = s.notes;

  readOptional(dir / "report.json", notes, [&](const std::string& p) {
    std::ifstream f(p);
    try {
      s.report = nlohmann::json::parse(f);
    } catch (const nlohmann::json::parse_error& e) {
      throw DataError::at(p, 0, std::string("not valid JSON: ") + e.what());
    }
    s.summary = parseRunSummary(s.report);
  });
  readOptional(dir / "trajectory.tum", notes, [&](const std::string& p) { s.trajectory = readTum(p); });
  readOptional(dir / "keyframes.tum", notes, [&](const std::string& p) { s.keyframes = readTum(p); });
  readOptional(dir / "points.ply", notes, [&](const std::string& p) { s.points = readPly(p); });
  readOptional(dir / "states.csv", notes, [&](const std::string& p) { s.states = readStates(p); });
  if (fs::exists(dir / "diagnostics.bin")) s.diagnostics_path = (dir / "diagnostics.bin").string();

  // Ground truth: an explicit file, else the dataset folder the report names. A relative "dataset" in
  // report.json is relative to the run folder first (a folder of that name beside the current
  // directory must not win); a relative --data of the caller is relative to the current directory.
  std::string dataset = options.dataset_dir.empty() ? s.summary.dataset : options.dataset_dir;
  const bool from_report = options.dataset_dir.empty();
  if (!dataset.empty() && fs::path(dataset).is_relative() && fs::is_directory(dir / dataset) &&
      (from_report || !fs::is_directory(dataset))) {
    dataset = (dir / dataset).string();
  }
  const bool have_dataset = !dataset.empty() && fs::is_directory(dataset);
  if (!dataset.empty() && !have_dataset) notes.push_back("dataset folder " + dataset + " not found: no ground truth");
  std::string gt_path = options.ground_truth_path;
  if (gt_path.empty() && have_dataset) {
    if (auto found = findDatasetGroundTruth(dataset)) gt_path = *found;
    else notes.push_back(dataset + ": dataset has no ground truth");
  }
  if (have_dataset) {
    const fs::path yaml = fs::path(dataset) / "mav0/cam0/sensor.yaml";
    if (fs::exists(yaml)) {
      try {
        s.T_B_C = eval::readSensorYamlTBS(yaml.string());
      } catch (const std::exception& e) {
        notes.push_back(e.what());
      }
    }
  }
  if (!gt_path.empty()) {
    try {
      Trajectory gt = readGroundTruth(gt_path);
      s.ground_truth_source = gt_path;
      if (s.poseFrame() == PoseFrame::kCamera && gt.frame == PoseFrame::kBody) {
        if (s.T_B_C) {
          gt = eval::mapBodyToCamera(gt, *s.T_B_C);
          s.ground_truth_source += " (body poses mapped to camera through T_BS)";
        } else {
          notes.push_back("camera-frame run but no sensor.yaml with T_BS: ground truth left unmapped");
          gt = Trajectory{};
        }
      }
      s.ground_truth = std::move(gt);
    } catch (const std::exception& e) {
      notes.push_back(e.what());
    }
  }
  s.errors = computeSnapshotErrors(s.trajectory, s.keyframes, s.ground_truth, s.summary.align, options.max_dt_ns,
                                   notes);
  return s;
}

}  // namespace rsvio::io
