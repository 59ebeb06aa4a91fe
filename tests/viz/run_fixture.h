// Synthetic run folders for the viz tests: the files `rsvio run` writes (user-contract.md), small and
// with known geometry, plus a dataset folder with EuRoC ground truth when asked.
#pragma once
#include <Eigen/Geometry>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <unistd.h>

#include "rsvio/io/ply.h"
#include "rsvio/io/states.h"
#include "rsvio/io/trajectory.h"

namespace rsvio::test {

namespace fs = std::filesystem;

// A fresh folder under the system temp dir, removed by the destructor.
struct TempDir {
  fs::path path;
  explicit TempDir(const std::string& tag) {
    path = fs::temp_directory_path() / ("rsvio_viz_" + tag + "_" + std::to_string(::getpid()));
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() {
    if (!std::getenv("RSVIO_KEEP_TEST_OUTPUT")) fs::remove_all(path);
  }
};

struct RunSpec {
  int n = 200;                     // frames, 20 Hz
  // Estimated position of frame i (world of the estimate).
  std::function<Eigen::Vector3d(int)> est = [](int i) { return Eigen::Vector3d(0.05 * i, 0, 0); };
  // Ground-truth position of frame i; empty: no dataset.
  std::function<Eigen::Vector3d(int)> gt;
  bool points = true;
  // Point i of the cloud (default: a ring of radius 4 m around (5, 0, 0)).
  std::function<Eigen::Vector3d(int)> point = [](int i) {
    const double a = i * 0.37;
    return Eigen::Vector3d(5.0 + 4.0 * std::cos(a), 3.0 * std::sin(a), 0.5 * std::sin(3 * a));
  };
  int n_points = 300;
  bool states = true;
  bool vo_states = false;          // states as a visual-odometry run writes them: only the twist is non-zero
  std::string frame = "body";
  std::string align;               // report.json eval.align ("" leaves eval out)
};

inline int64_t frameTime(int i) { return 1'000'000'000LL + 50'000'000LL * i; }

// Writes <dir>/run (the run) and, with spec.gt, <dir>/data (EuRoC layout). Returns the run folder.
inline fs::path makeRun(const fs::path& dir, const RunSpec& spec) {
  const fs::path run = dir / "run";
  fs::create_directories(run);
  io::Trajectory tr, kf;
  tr.frame = kf.frame = spec.frame == "camera" ? io::PoseFrame::kCamera : io::PoseFrame::kBody;
  for (int i = 0; i < spec.n; ++i) {
    io::StampedPose p;
    p.t_ns = frameTime(i);
    p.p_W_X = spec.est(i);
    tr.poses.push_back(p);
    if (i % 5 == 0) kf.poses.push_back(p);
  }
  io::writeTum((run / "trajectory.tum").string(), tr);
  io::writeTum((run / "keyframes.tum").string(), kf);
  nlohmann::json report = {{"status", "ok"}, {"frames", spec.n}, {"keyframes", kf.size()}, {"fps", 87.5},
                           {"realtime_factor", 4.375}, {"stage_ms", {{"tracking", 6.1}, {"mapping", 3.4}}}};
  if (spec.gt) {
    const fs::path gt_dir = dir / "data/mav0/state_groundtruth_estimate0";
    fs::create_directories(gt_dir);
    std::ofstream g(gt_dir / "data.csv");
    g << "#timestamp,p_x,p_y,p_z,q_w,q_x,q_y,q_z,v_x,v_y,v_z,bw_x,bw_y,bw_z,ba_x,ba_y,ba_z\n";
    for (int i = 0; i < spec.n; ++i) {
      const Eigen::Vector3d p = spec.gt(i);
      g << frameTime(i) << "," << p.x() << "," << p.y() << "," << p.z() << ",1,0,0,0,0,0,0,0,0,0,0,0,0\n";
    }
    report["dataset"] = (dir / "data").string();
    if (!spec.align.empty()) report["eval"] = {{"ate_rmse_m", 0.1}, {"align", spec.align}};
  }
  std::ofstream(run / "report.json") << report.dump(2);
  if (spec.points) {
    io::PointCloud pc;
    for (int i = 0; i < spec.n_points; ++i) {
      pc.p_W.push_back(spec.point(i));
      pc.intensity.push_back(static_cast<float>(i % 255));
    }
    io::writePly((run / "points.ply").string(), pc);
  }
  if (spec.states) {
    std::vector<StateRow> rows;
    for (int i = 0; i < spec.n; i += 5) {
      StateRow r;
      r.t_ns = frameTime(i);
      r.v = Eigen::Vector3d(1.0, 0.1 * std::sin(0.1 * i), 0);
      r.bg = Eigen::Vector3d(1e-3, -2e-3, 5e-4);
      r.ba = Eigen::Vector3d(0.01 * std::cos(0.05 * i), 0.02, -0.01);
      r.twist << 1.0, 0, 0, 0, 0, 0.05 * std::sin(0.1 * i);
      r.scale = 1.0 + 0.001 * i;
      r.time_offset_ms = 15.0 * (1.0 - std::exp(-0.05 * i));  // estimated online, converging
      r.line_delay_us = 58.94 * (1.0 - 0.5 * std::exp(-0.05 * i));  // the same, from half
      if (spec.vo_states) {
        r.v.setZero();
        r.bg.setZero();
        r.ba.setZero();
        r.scale = 1.0;
        r.time_offset_ms = 0.0;
        r.line_delay_us = 0.0;
      }
      rows.push_back(r);
    }
    writeStates(rows, (run / "states.csv").string());
  }
  return run;
}

// A run that failed before tracking anything: report.json only.
inline fs::path makeFailedRun(const fs::path& dir, const std::string& error) {
  const fs::path run = dir / "failed_run";
  fs::create_directories(run);
  std::ofstream(run / "report.json") << nlohmann::json{{"status", "failed"}, {"error", error}, {"frames", 12}}.dump(2);
  return run;
}

// Pixel helpers on a BGR image.
inline bool isSaturated(const cv::Vec3b& p, int min_spread = 60) {
  const int mx = std::max({p[0], p[1], p[2]}), mn = std::min({p[0], p[1], p[2]});
  return mx - mn >= min_spread;
}

}  // namespace rsvio::test
