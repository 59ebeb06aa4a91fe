// Helpers of the estimator tests: tiny simulator datasets made once per test process with
// `$RSVIO_BIN simulate`, run configs from configs/*.json validated like `rsvio run` does, and a loop
// that feeds a dataset to rsvio::Odometry (optionally replacing images) and evaluates the keyframes.
#pragma once
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <functional>
#include <map>
#include <string>

#include "rsvio/config/config.h"
#include "rsvio/config/validate.h"
#include "rsvio/eval/trajectory_metrics.h"
#include "rsvio/interfaces/data_source.h"
#include "rsvio/io/trajectory.h"
#include "rsvio/plugin/host.h"
#include "rsvio/system/odometry.h"
#include "support/plugin_contracts.h"

namespace rsvio::test {

// <tmp>/rsvio_be_<pid>/<name>: simulated once from configs/sim/<name>.json (+ sets).
inline std::string simDataset(const std::string& name, const std::string& sets = "") {
  static std::map<std::string, std::string> made;
  const std::string key = name + "|" + sets;
  if (made.count(key)) return made[key];
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("rsvio_be_" + std::to_string(::getpid())) / (name + std::to_string(made.size()));
  std::filesystem::create_directories(dir.parent_path());
  const char* bin = std::getenv("RSVIO_BIN");
  const std::string exe = bin ? bin : std::string(RSVIO_BINARY_DIR) + "/bin/rsvio";
  const std::string cmd = exe + " simulate --config " + std::string(RSVIO_SOURCE_DIR) + "/configs/sim/" + name +
                          ".json --out " + dir.string() + " " + sets + " > " + dir.string() + ".log 2>&1";
  if (std::system(cmd.c_str()) != 0) ADD_FAILURE() << "simulation failed: " << cmd;
  made[key] = dir.string();
  return dir.string();
}

// configs/<name>.json with --set lines, validated against the run schema (defaults filled).
inline nlohmann::json runConfig(const std::string& name, const std::vector<std::string>& sets = {}) {
  nlohmann::json cfg = loadConfigWithSets(std::string(RSVIO_SOURCE_DIR) + "/configs/" + name + ".json", sets);
  return validateConfig(cfg, runConfigSchema(), contractHost(), name + ".json");
}

struct RunOutcome {
  bool failed = false;
  std::string reason;
  long frames = 0;
  long tracked = 0;
  long first_tracked = -1;      // index of the first frame with a pose
  long untracked_after_first = 0;
  long keyframes = 0;
  io::Trajectory frame_traj, kf_traj;
  std::vector<std::string> messages;
  std::vector<std::string> warnings;  // Odometry::warnings() after finish()
  std::map<std::string, double> stage_ms;
  size_t diagnostics_rows = 0;
  double ate_rmse_m = -1.0;     // keyframes, Sim(3), against the dataset's camera ground truth (VO)
  double path_m = 0.0;
  nlohmann::json vio;           // Odometry::inertialReport() (null for VO)
  nlohmann::json shutter;       // Odometry::shutterReport() (null for a global shutter)
};

// Feeds the dataset to the estimator. `modify(i, frame)` may replace images (broken-input tests).
// `imu_modify(sample)` may change IMU samples before the estimator sees them. `after(odo, i)` is called
// after frame i and once after finish() with i = kAfterFinish (to take rows and points as `rsvio run`
// streams them).
constexpr size_t kAfterFinish = static_cast<size_t>(-1);
inline RunOutcome runDataset(const std::string& dataset, const nlohmann::json& cfg, long max_frames = -1,
                             const std::function<void(size_t, Frame&)>& modify = nullptr,
                             const std::function<void(ImuSample&)>& imu_modify = nullptr,
                             const std::function<void(Odometry&, size_t)>& after = nullptr) {
  PluginHost& host = contractHost();
  auto source = host.create<DataSource>(cfg.at("source").at("plugin").get<std::string>(), slotParams(cfg, "source"));
  source->open(dataset);
  Odometry odo(cfg, host, source->sensors());
  RunOutcome out;
  const std::vector<ImuSample>& imu = source->imu();
  size_t k = 0;
  const size_t n = max_frames > 0 ? std::min<size_t>(max_frames, source->numFrames()) : source->numFrames();
  for (size_t i = 0; i < n; ++i) {
    Frame f = source->readFrame(i);
    while (k < imu.size() && imu[k].t_ns <= f.t_ns) {
      ImuSample s = imu[k++];
      if (imu_modify) imu_modify(s);
      odo.addImu(s);
    }
    if (modify) modify(i, f);
    const FrameStatus s = odo.addFrame(f);
    ++out.frames;
    out.messages.push_back(s.message);
    if (s.tracked) {
      ++out.tracked;
      if (out.first_tracked < 0) out.first_tracked = static_cast<long>(i);
    } else if (out.first_tracked >= 0) {
      ++out.untracked_after_first;
    }
    if (after) after(odo, i);
    if (odo.failed()) break;
  }
  odo.finish();
  if (after) after(odo, kAfterFinish);
  out.failed = odo.failed();
  out.reason = odo.failureReason();
  out.keyframes = odo.numKeyframes();
  out.frame_traj = odo.frameTrajectory();
  out.kf_traj = odo.keyframeTrajectory();
  out.stage_ms = odo.stageMs();
  out.diagnostics_rows = odo.diagnostics().observations.size();
  out.vio = odo.inertialReport();
  out.shutter = odo.shutterReport();
  out.warnings = odo.warnings();
  // Camera ground truth: body poses mapped through the calibration's T_B_C.
  const auto gt_path = io::findDatasetGroundTruth(dataset);
  if (gt_path && out.kf_traj.size() >= 3 && out.kf_traj.frame == io::PoseFrame::kCamera) {
    io::Trajectory gt = io::readGroundTruth(*gt_path);
    const Eigen::Isometry3d T_B_C = source->sensors().camera.T_B_C;
    for (io::StampedPose& p : gt.poses) {
      Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
      T.linear() = p.q_W_X.toRotationMatrix();
      T.translation() = p.p_W_X;
      const Eigen::Isometry3d T_W_C = T * T_B_C;
      p.p_W_X = T_W_C.translation();
      p.q_W_X = Eigen::Quaterniond(T_W_C.linear());
    }
    gt.frame = io::PoseFrame::kCamera;
    eval::EvalOptions eo;
    eo.align = eval::AlignMode::kSim3;
    const eval::EvalResult r = eval::evaluateTrajectory(gt, out.kf_traj, eo);
    out.ate_rmse_m = r.ate_m.rmse;
    out.path_m = r.gt_path_length_m;
  }
  return out;
}

}  // namespace rsvio::test
