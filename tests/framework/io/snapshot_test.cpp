// Snapshot of a run folder: lenient reading (a failed run still yields one), ground truth from the
// dataset the report names, camera-frame runs compared through T_BS with Sim(3), body-frame with SE(3).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include "rsvio/core/error.h"
#include "rsvio/io/ply.h"
#include "rsvio/io/snapshot.h"
#include "rsvio/io/states.h"
#include "rsvio/io/trajectory.h"

namespace rsvio::io {
namespace {
namespace fs = std::filesystem;

struct Tmp {
  fs::path path;
  explicit Tmp(const std::string& tag) {
    path = fs::temp_directory_path() / ("rsvio_snapshot_" + tag + "_" + std::to_string(::getpid()));
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~Tmp() { fs::remove_all(path); }
};

int64_t stamp(int i) { return 2'000'000'000LL + 50'000'000LL * i; }

// Ground-truth body pose i: a circle with yaw following the path and some roll.
Eigen::Isometry3d gtPose(int i) {
  const double a = 0.03 * i;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = (Eigen::AngleAxisd(a + 1.0, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(0.2 * std::sin(a), Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  T.translation() = Eigen::Vector3d(3 * std::cos(a), 3 * std::sin(a), 1.0 + 0.3 * std::sin(2 * a));
  return T;
}

Eigen::Isometry3d tBS() {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = (Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(0.05, Eigen::Vector3d::UnitY()))
                   .toRotationMatrix();
  T.translation() = Eigen::Vector3d(0.05, -0.02, 0.01);
  return T;
}

void writeDataset(const fs::path& data, int n) {
  fs::create_directories(data / "mav0/state_groundtruth_estimate0");
  fs::create_directories(data / "mav0/cam0");
  std::ofstream g(data / "mav0/state_groundtruth_estimate0/data.csv");
  g.precision(12);
  g << "#timestamp,p_x,p_y,p_z,q_w,q_x,q_y,q_z,v_x,v_y,v_z,bw_x,bw_y,bw_z,ba_x,ba_y,ba_z\n";
  for (int i = 0; i < n; ++i) {
    const auto T = gtPose(i);
    const Eigen::Quaterniond q(T.linear());
    g << stamp(i) << "," << T.translation().x() << "," << T.translation().y() << "," << T.translation().z() << "," << q.w()
      << "," << q.x() << "," << q.y() << "," << q.z() << ",0,0,0,0,0,0,0,0,0\n";
  }
  std::ofstream y(data / "mav0/cam0/sensor.yaml");
  y.precision(15);
  const Eigen::Matrix4d M = tBS().matrix();
  y << "sensor_type: camera\nT_BS:\n  cols: 4\n  rows: 4\n  data: [";
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) y << M(r, c) << (r == 3 && c == 3 ? "]\n" : ", ");
  }
}

// The estimate: the ground truth (body or camera poses) seen through a similarity s, R, t.
void writeRun(const fs::path& run, int n, PoseFrame frame, double s, const Eigen::Matrix3d& R, const Eigen::Vector3d& t,
              const nlohmann::json& report) {
  fs::create_directories(run);
  Trajectory tr, kf;
  tr.frame = kf.frame = frame;
  for (int i = 0; i < n; ++i) {
    const Eigen::Isometry3d T = frame == PoseFrame::kCamera ? gtPose(i) * tBS() : gtPose(i);
    StampedPose p;
    p.t_ns = stamp(i);
    p.p_W_X = s * R * T.translation() + t;
    p.q_W_X = Eigen::Quaterniond(R * T.linear());
    tr.poses.push_back(p);
    if (i % 4 == 0) kf.poses.push_back(p);
  }
  writeTum((run / "trajectory.tum").string(), tr);
  writeTum((run / "keyframes.tum").string(), kf);
  std::ofstream(run / "report.json") << report.dump(2);
}

TEST(Snapshot, BodyFrameRunIsComparedWithSE3AndErrorsVanish) {
  Tmp tmp("body");
  writeDataset(tmp.path / "data", 120);
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  writeRun(tmp.path / "run", 120, PoseFrame::kBody, 1.0, R, Eigen::Vector3d(1, -2, 0.5),
           {{"status", "ok"}, {"frames", 120}, {"dataset", (tmp.path / "data").string()}, {"stage_ms", {{"b", 2}, {"a", 1}}}});
  PointCloud pc;
  pc.p_W = {{1, 2, 3}};
  pc.intensity = {7};
  writePly((tmp.path / "run/points.ply").string(), pc);
  writeStates({StateRow{}, StateRow{}}, (tmp.path / "run/states.csv").string());

  const Snapshot s = readSnapshot((tmp.path / "run").string());
  EXPECT_EQ(s.name, "run");
  EXPECT_EQ(s.summary.status, "ok");
  EXPECT_EQ(s.summary.frames, 120);
  ASSERT_EQ(s.summary.stage_ms.size(), 2u);
  EXPECT_EQ(s.trajectory.size(), 120u);
  EXPECT_EQ(s.keyframes.size(), 30u);
  EXPECT_EQ(s.points.size(), 1u);
  EXPECT_EQ(s.states.size(), 2u);
  EXPECT_EQ(s.ground_truth.frame, PoseFrame::kBody);
  ASSERT_TRUE(s.T_B_C.has_value());
  ASSERT_TRUE(s.errors.has_value()) << (s.notes.empty() ? "" : s.notes.back());
  EXPECT_EQ(s.errors->alignment.mode, eval::AlignMode::kSE3);
  EXPECT_EQ(s.errors->aligned_on, "keyframes");
  EXPECT_EQ(s.errors->ate_m.n, 30u);
  EXPECT_LT(s.errors->ate_m.rmse, 1e-6);
  EXPECT_EQ(s.errors->frames.size(), 120u);
  // The alignment undoes R: the estimate is mapped back into the ground truth's world.
  EXPECT_LT((s.errors->alignment.R - R.transpose()).norm(), 1e-6);
  for (const auto& e : s.errors->frames) EXPECT_LT(e.err_m, 1e-6);
}

TEST(Snapshot, CameraFrameRunIsMappedThroughTBSAndSim3Aligned) {
  Tmp tmp("camera");
  writeDataset(tmp.path / "data", 100);
  const Eigen::Matrix3d R = Eigen::AngleAxisd(-0.4, Eigen::Vector3d::UnitY()).toRotationMatrix();
  // The dataset path relative to the run folder works too.
  writeRun(tmp.path / "run", 100, PoseFrame::kCamera, 0.25, R, Eigen::Vector3d(0.3, 0, 0),
           {{"status", "ok"}, {"dataset", "../data"}});
  const Snapshot s = readSnapshot((tmp.path / "run").string());
  EXPECT_EQ(s.poseFrame(), PoseFrame::kCamera);
  EXPECT_EQ(s.ground_truth.frame, PoseFrame::kCamera);
  ASSERT_TRUE(s.errors.has_value()) << (s.notes.empty() ? "" : s.notes.back());
  EXPECT_EQ(s.errors->alignment.mode, eval::AlignMode::kSim3);
  EXPECT_NEAR(s.errors->alignment.scale, 4.0, 1e-6);
  EXPECT_LT(s.errors->ate_m.rmse, 1e-6);
}

TEST(Snapshot, ReportAlignIsHonoured) {
  Tmp tmp("align");
  writeDataset(tmp.path / "data", 60);
  writeRun(tmp.path / "run", 60, PoseFrame::kBody, 2.0, Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero(),
           {{"status", "ok"}, {"dataset", (tmp.path / "data").string()}, {"eval", {{"ate_rmse_m", 0.0}, {"align", "sim3"}}}});
  const Snapshot s = readSnapshot((tmp.path / "run").string());
  ASSERT_TRUE(s.errors.has_value());
  EXPECT_EQ(s.errors->alignment.mode, eval::AlignMode::kSim3);
  EXPECT_EQ(s.errors->align_reason, "report.json eval.align");
  EXPECT_NEAR(s.errors->alignment.scale, 0.5, 1e-9);
  EXPECT_EQ(s.summary.align, "sim3");
}

TEST(Snapshot, FailedRunWithOnlyAReportStillYieldsASnapshot) {
  Tmp tmp("failed");
  std::ofstream(tmp.path / "report.json") << R"({"status": "failed", "error": "diverged at frame 3"})";
  const Snapshot s = readSnapshot(tmp.path.string());
  EXPECT_TRUE(s.failed());
  EXPECT_EQ(s.summary.error, "diverged at frame 3");
  EXPECT_TRUE(s.trajectory.empty());
  EXPECT_FALSE(s.errors.has_value());
  bool noted = false;
  for (const auto& n : s.notes) noted |= n.find("trajectory.tum") != std::string::npos;
  EXPECT_TRUE(noted);
}

TEST(Snapshot, MalformedFilesBecomeNotesNamingFileAndLine) {
  Tmp tmp("bad");
  std::ofstream(tmp.path / "report.json") << "{ not json";
  std::ofstream(tmp.path / "trajectory.tum") << "# frame: body\n1.0 0 0 0 0 0 0 1\n2.0 0 zero 0 0 0 0 1\n";
  const Snapshot s = readSnapshot(tmp.path.string());
  EXPECT_EQ(s.summary.status, "unknown");
  bool report = false, traj = false;
  for (const auto& n : s.notes) {
    report |= n.find("report.json") != std::string::npos;
    traj |= n.find("trajectory.tum:3") != std::string::npos;
  }
  EXPECT_TRUE(report);
  EXPECT_TRUE(traj);
  EXPECT_THROW(readSnapshot((tmp.path / "does_not_exist").string()), DataError);
}

TEST(Snapshot, TooFewKeyframesFallBackToTheFrameTrajectory) {
  Trajectory gt, tr, kf;
  gt.frame = tr.frame = kf.frame = PoseFrame::kBody;
  for (int i = 0; i < 20; ++i) {
    StampedPose p;
    p.t_ns = stamp(i);
    p.p_W_X = gtPose(i).translation();
    gt.poses.push_back(p);
    tr.poses.push_back(p);
    if (i < 2) kf.poses.push_back(p);
  }
  std::vector<std::string> notes;
  const auto e = computeSnapshotErrors(tr, kf, gt, "", 10'000'000, notes);
  ASSERT_TRUE(e.has_value());
  EXPECT_EQ(e->aligned_on, "trajectory");
  EXPECT_EQ(e->frames.size(), 20u);
  // No ground truth: no errors, no exception.
  EXPECT_FALSE(computeSnapshotErrors(tr, kf, Trajectory{}, "", 10'000'000, notes).has_value());
}

}  // namespace
}  // namespace rsvio::io
