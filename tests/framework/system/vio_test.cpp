// The visual-inertial estimator end to end on tiny simulated sequences (320x256, 3 s, IMU at 200 Hz):
// the visual-inertial initialisation, metric body poses (SE(3) ATE against the body ground truth, the
// Sim(3) scale near 1, gravity: the alignment rotation is a yaw), the run that cannot initialise and
// keeps tracking visually, and divergence detected when the accelerometer breaks after the start.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "odometry_test_util.h"
#include "rsvio/eval/trajectory_metrics.h"

namespace rsvio {
namespace {

using test::runConfig;
using test::simDataset;

struct VioOutcome : test::RunOutcome {
  double ate_se3_m = -1, sim3_scale = 0, tilt_deg = 180, ate_sim3_m = -1;
};

// runDataset (odometry_test_util.h), then body-frame keyframes against the body ground truth (SE(3)
// and Sim(3)); camera-frame estimates are not evaluated here.
VioOutcome runVio(const std::string& dataset, const nlohmann::json& cfg,
                  const std::function<void(ImuSample&)>& imu_modify = nullptr) {
  VioOutcome out;
  static_cast<test::RunOutcome&>(out) = test::runDataset(dataset, cfg, -1, nullptr, imu_modify);
  const auto gt_path = io::findDatasetGroundTruth(dataset);
  if (gt_path && out.kf_traj.frame == io::PoseFrame::kBody && out.kf_traj.size() >= 3) {
    io::Trajectory gt = io::readGroundTruth(*gt_path);
    gt.frame = io::PoseFrame::kBody;
    eval::EvalOptions eo;
    eo.align = eval::AlignMode::kSE3;
    const eval::EvalResult r = eval::evaluateTrajectory(gt, out.kf_traj, eo);
    out.ate_se3_m = r.ate_m.rmse;
    out.path_m = r.gt_path_length_m;
    // Gravity: with z up in both worlds the aligning rotation must be a rotation about z.
    out.tilt_deg = std::acos(std::clamp(r.alignment.R(2, 2), -1.0, 1.0)) * 180.0 / M_PI;
    eo.align = eval::AlignMode::kSim3;
    const eval::EvalResult s = eval::evaluateTrajectory(gt, out.kf_traj, eo);
    out.sim3_scale = s.alignment.scale;
    out.ate_sim3_m = s.ate_m.rmse;
  }
  return out;
}

// Measured (tiny_gs, seed of the config): initialised at 1.6 s, SE(3) ATE 3.8 mm, Sim(3) scale ~1.00.
TEST(VisualInertial, TinyGlobalShutterSequenceGetsMetricScaleAndGravity) {
  const std::string data = simDataset("tiny_gs");
  const VioOutcome r = runVio(data, runConfig("gs_vio"));
  ASSERT_FALSE(r.failed) << r.reason;
  ASSERT_TRUE(r.vio.is_object());
  ASSERT_TRUE(r.vio.at("initialised").get<bool>()) << r.vio.dump();
  EXPECT_EQ(r.untracked_after_first, 0);
  ASSERT_EQ(r.kf_traj.frame, io::PoseFrame::kBody);
  ASSERT_GT(r.path_m, 0.5);
  EXPECT_LT(r.ate_se3_m, 0.01 * r.path_m) << "SE(3) ATE " << r.ate_se3_m << " m over " << r.path_m << " m";
  EXPECT_NEAR(r.sim3_scale, 1.0, 0.03) << "the metric scale is off";
  EXPECT_LT(r.tilt_deg, 2.0) << "gravity direction off by " << r.tilt_deg << " deg";
  EXPECT_GT(r.vio.at("scale").get<double>(), 0.0);
}

// A tiny_rs run of rs_vio: initialised, every frame tracked after the first, SE(3) ATE below 1.5 % of
// the path, Sim(3) scale within 5 %.
void expectTinyRollingShutterRunAccurate(const VioOutcome& r) {
  ASSERT_FALSE(r.failed) << r.reason;
  ASSERT_TRUE(r.vio.at("initialised").get<bool>()) << r.vio.dump();
  EXPECT_EQ(r.untracked_after_first, 0);
  ASSERT_GT(r.path_m, 0.5);
  EXPECT_LT(r.ate_se3_m, 0.015 * r.path_m) << "SE(3) ATE " << r.ate_se3_m << " m over " << r.path_m << " m";
  EXPECT_NEAR(r.sim3_scale, 1.0, 0.05);
}

// The paper's method on the tiny rolling-shutter sequence with the true line delay, after the plain
// two-view start (tiny_rs's 0.15 s start is too short for the rate-corrected one: odometry_test.cpp).
TEST(VisualInertial, TinyRollingShutterSequenceWithTwistEnergy) {
  const std::string data = simDataset("tiny_rs");
  const VioOutcome r = runVio(data, runConfig("rs_vio", {"shutter.params.line_delay_us=117.88",
                                                         "backend.init_rotation_rates=false"}));
  expectTinyRollingShutterRunAccurate(r);
}

// The same with the gyroscope's rotations in the window before the initialisation
// (imu.gyro_bias_sigma_before_init_rad_s, off by default): its terms enter the bundle adjustment and,
// as keyframes leave, the marginalisation prior, before the layout gains the inertial blocks; the run
// still initialises and stays as accurate. Shown once that the prior's path is reached: a term one row
// short handed to the prior there makes the run fail.
TEST(VisualInertial, TinyRollingShutterSequenceWithTheGyroscopeBeforeTheInitialisation) {
  const std::string data = simDataset("tiny_rs");
  const VioOutcome r =
      runVio(data, runConfig("rs_vio", {"shutter.params.line_delay_us=117.88", "backend.init_rotation_rates=false",
                                        "imu.gyro_bias_sigma_before_init_rad_s=0.005"}));
  expectTinyRollingShutterRunAccurate(r);
}

// Without the excitation the initialisation asks for, the run stays visual odometry all through and
// says why; its outputs are camera poses.
TEST(VisualInertial, WithoutEnoughExcitationItKeepsTrackingVisuallyAndSaysWhy) {
  const std::string data = simDataset("tiny_gs");
  const VioOutcome r = runVio(data, runConfig("gs_vio", {"imu.init_min_accel_excitation_m_s2=1000"}));
  ASSERT_FALSE(r.failed) << r.reason;
  EXPECT_FALSE(r.vio.at("initialised").get<bool>());
  EXPECT_NE(r.vio.at("status").get<std::string>().find("excitation"), std::string::npos) << r.vio.dump();
  EXPECT_EQ(r.untracked_after_first, 0);
  EXPECT_EQ(r.kf_traj.frame, io::PoseFrame::kCamera);
  EXPECT_GE(r.tracked, 40);
}

// An initialisation whose every attempt is refused (imu.init_max_imu_chi2 below any fit) says how often
// and why from the first refusal on (report.json extra.vio: init_refusals, init_first_refusal_at_s,
// init_first_refusal). Measured on tiny_gs: the default run is refused twice (accelerometer bias, at
// 1.6 and 1.7 s) and initialises at 1.8 s; with the bound every attempt after is refused too. Shown
// once: with the refusals not counted the test fails (0 against more than 2).
TEST(VisualInertial, RefusedInitialisationsAreCountedWithTheFirstReason) {
  const std::string data = simDataset("tiny_gs");
  const VioOutcome ok = runVio(data, runConfig("gs_vio", {}));
  ASSERT_TRUE(ok.vio.at("initialised").get<bool>()) << ok.vio.dump();
  const int ok_refusals = ok.vio.at("init_refusals").get<int>();
  if (ok_refusals > 0)
    EXPECT_LE(ok.vio.at("init_first_refusal_at_s").get<double>(), ok.vio.at("initialised_at_s").get<double>());
  else
    EXPECT_FALSE(ok.vio.contains("init_first_refusal"));

  const VioOutcome r = runVio(data, runConfig("gs_vio", {"imu.init_max_imu_chi2=1e-12"}));
  ASSERT_FALSE(r.failed) << r.reason;
  EXPECT_FALSE(r.vio.at("initialised").get<bool>());
  EXPECT_GT(r.vio.at("init_refusals").get<int>(), ok_refusals + 2) << r.vio.dump();
  EXPECT_NE(r.vio.at("status").get<std::string>().find("init_max_imu_chi2"), std::string::npos) << r.vio.dump();
  EXPECT_NE(r.vio.at("init_first_refusal").get<std::string>().find("refused"), std::string::npos) << r.vio.dump();
  EXPECT_GT(r.vio.at("init_first_refusal_at_s").get<double>(), 0.0);
}

// A run initialised only after imu.init_refusals_warn refusals ends with a warning that its start may
// be broken (Table I's seq02 seeds 2-3: 40 and 42 refusals, 830 and 231 mm, reported "ok" without it;
// the default bound 20 lies above the 0-11 refusals of 56 runs that ended well, docs/vio.md). On tiny_gs
// the default run is refused twice (the test above): no warning at the default bound, the warning with
// the bound at its count, none with the bound just above it. Shown once: with the warning's test
// removed from Odometry::finish this fails.
TEST(VisualInertial, ALateInitialisationAfterManyRefusalsIsAWarning) {
  const std::string data = simDataset("tiny_gs");
  auto refusal_warnings = [](const VioOutcome& r) {
    int n = 0;
    for (const std::string& w : r.warnings) n += w.find("refused attempts") != std::string::npos;
    return n;
  };
  const VioOutcome ok = runVio(data, runConfig("gs_vio", {}));
  ASSERT_TRUE(ok.vio.at("initialised").get<bool>()) << ok.vio.dump();
  const int refusals = ok.vio.at("init_refusals").get<int>();
  ASSERT_GT(refusals, 0) << "tiny_gs's default run is no longer refused: this test needs a run that is";
  EXPECT_EQ(refusal_warnings(ok), 0);
  const std::string at = "imu.init_refusals_warn=" + std::to_string(refusals);
  const VioOutcome warned = runVio(data, runConfig("gs_vio", {at}));
  ASSERT_TRUE(warned.vio.at("initialised").get<bool>());
  ASSERT_EQ(refusal_warnings(warned), 1) << warned.vio.dump();
  for (const std::string& w : warned.warnings)
    if (w.find("refused attempts") != std::string::npos) {
      EXPECT_NE(w.find(std::to_string(refusals) + " refused attempts"), std::string::npos) << w;
      EXPECT_NE(w.find("refused: biases"), std::string::npos) << "names the first refusal's reason: " << w;
    }
  const VioOutcome above = runVio(data, runConfig("gs_vio", {"imu.init_refusals_warn=" + std::to_string(refusals + 1)}));
  EXPECT_EQ(refusal_warnings(above), 0);
}

// An accelerometer that reads 20 m/s^2 too much on x from 2 s on (after the initialisation) cannot be
// explained by a slowly walking bias: the run fails with an inertial divergence reason.
TEST(VisualInertial, ABrokenAccelerometerAfterTheStartIsReportedAsDivergence) {
  const std::string data = simDataset("tiny_gs");
  int64_t t0 = -1;
  const VioOutcome r = runVio(data, runConfig("gs_vio"), [&](ImuSample& s) {
    if (t0 < 0) t0 = s.t_ns;
    if (s.t_ns - t0 > 2'000'000'000) s.accel_m_s2.x() += 20.0;
  });
  ASSERT_TRUE(r.failed) << "the broken accelerometer went unnoticed";
  EXPECT_TRUE(r.reason.find("IMU residuals") != std::string::npos || r.reason.find("bias runaway") != std::string::npos ||
              r.reason.find("scale collapse") != std::string::npos)
      << r.reason;
}

// The window's IMU energy against its own level (imu.fail_sustained_*, gs_vio.json: 1000 and 10x the
// level for 1 s; the sequence is 2.85 s long with the initialisation at 1.8 s, so the test starts at
// the initialisation, imu.fail_grace_s 0, and takes the level and the stretch over 0.3 s):
// - an accelerometer that shakes by 12 m/s^2 at 5 Hz on x from 2.15 s on leaves the window off the IMU
//   for good without tripping the other limits (about 1800 per factor against a level of 66): with the
//   test off the run ends "ok" at 5x the clean error (23.0 against 4.5 mm, measured), with it it fails;
// - the IMU clock 15 ms ahead (an unmodelled time offset) holds the energy high from the start (median
//   4377): not a break, so the run goes on, with the warning that the model does not fit the IMU
//   (imu.warn_imu_chi2). Shown once: with the level held at 0 (the limit alone) this run fails.
TEST(VisualInertial, AWindowThatBreaksOffTheImuFailsTheRunAnUnmodelledOffsetWarns) {
  const std::string data = simDataset("tiny_gs");
  int64_t t0 = -1;
  auto shake = [&](ImuSample& s) {
    if (t0 < 0) t0 = s.t_ns;
    const double t = 1e-9 * static_cast<double>(s.t_ns - t0);
    if (t > 2.15) s.accel_m_s2.x() += 12.0 * std::sin(2.0 * M_PI * 5.0 * t);
  };
  auto imu_warnings = [](const VioOutcome& r) {
    int n = 0;
    for (const std::string& w : r.warnings) n += w.find("IMU residuals stayed high") != std::string::npos;
    return n;
  };
  const std::vector<std::string> quick = {"imu.fail_grace_s=0", "imu.fail_sustained_s=0.3"};
  const VioOutcome clean = runVio(data, runConfig("gs_vio", quick));
  ASSERT_FALSE(clean.failed) << clean.reason;
  ASSERT_TRUE(clean.vio.at("initialised").get<bool>());
  EXPECT_EQ(imu_warnings(clean), 0);
  std::vector<std::string> off = quick;
  off.push_back("imu.fail_sustained_imu_chi2=0");
  t0 = -1;
  const VioOutcome unnoticed = runVio(data, runConfig("gs_vio", off), shake);
  EXPECT_FALSE(unnoticed.failed) << "the other limits see this shake now; find one only the sustained test sees: "
                                 << unnoticed.reason;
  t0 = -1;
  const VioOutcome broke = runVio(data, runConfig("gs_vio", quick), shake);
  ASSERT_TRUE(broke.failed) << "the shaken accelerometer went unnoticed";
  EXPECT_NE(broke.reason.find("IMU residuals stay high"), std::string::npos) << broke.reason;
  const VioOutcome offset =
      runVio(data, runConfig("gs_vio", quick), [](ImuSample& s) { s.t_ns += 15'000'000; });
  EXPECT_FALSE(offset.failed) << offset.reason;
  EXPECT_EQ(imu_warnings(offset), 1);
}

// A run streamed as `rsvio run` streams it (observation rows and points taken after every frame), with
// the frames of the restarts it reports.
struct StreamedRun {
  test::RunOutcome out;
  std::vector<ObservationRow> rows;
  std::vector<long> points_taken_at;  // per taken point: the frame after which it was taken
  std::vector<int64_t> restart_frames;
};

StreamedRun runStreamed(const std::string& dataset, const nlohmann::json& cfg,
                        const std::function<void(size_t, Frame&)>& modify = nullptr) {
  StreamedRun r;
  std::vector<MapPoint> points;
  r.out = test::runDataset(dataset, cfg, -1, modify, nullptr, [&](Odometry& odo, size_t i) {
    odo.takeDiagnostics(&r.rows);
    if (i == test::kAfterFinish) return;
    const size_t before = points.size();
    odo.takePoints(&points);
    r.points_taken_at.insert(r.points_taken_at.end(), points.size() - before, static_cast<long>(i));
  });
  if (r.out.vio.is_object() && r.out.vio.contains("start_restarts"))
    for (const auto& e : r.out.vio.at("start_restarts")) r.restart_frames.push_back(e.at("frame").get<int64_t>());
  return r;
}

// The restart of a start (imu.init_restart_refusals): with every initialisation refused
// (imu.init_max_imu_chi2 below any fit) and a restart after 3 refusals, at most one, the run discards
// its first attempt once, starts again and tracks on. Nothing of the discarded attempt reaches the
// outputs: no pose of a frame up to the restart, no observation row of a frame or host up to it, no
// point taken before it (the record is provisional until then). Without the restart the same run writes
// rows of those frames (so the row check can fail). Shown once: with RunRecord::takeObservations and
// takePoints not holding back while provisional, the row and point checks fail here and the row check of
// the next test fails; with RunRecord::restart leaving the frames tracked, the pose check fails.
TEST(VisualInertial, AStartTheImuDoesNotFitIsBegunAgainAndNothingOfItIsWritten) {
  const std::string data = simDataset("tiny_gs");
  const StreamedRun r = runStreamed(data, runConfig("gs_vio", {"imu.init_max_imu_chi2=1e-12",
                                                               "imu.init_restart_refusals=3", "imu.init_max_restarts=1"}));
  ASSERT_FALSE(r.out.failed) << r.out.reason;
  ASSERT_EQ(r.restart_frames.size(), 1u) << r.out.vio.dump();
  const int64_t R = r.restart_frames[0];
  EXPECT_NE(r.out.vio.at("start_restarts")[0].at("reason").get<std::string>().find("refused 3 times"),
            std::string::npos) << r.out.vio.dump();
  EXPECT_FALSE(r.out.vio.at("initialised").get<bool>());
  ASSERT_GE(r.out.frame_traj.size(), 10u) << "the second attempt tracks";
  const int64_t t_restart = r.out.frame_traj.poses.front().t_ns;
  int64_t rows_before = 0;
  for (const ObservationRow& o : r.rows) rows_before += o.frame <= R || o.host <= R;
  EXPECT_EQ(rows_before, 0) << "observation rows of the discarded attempt were written";
  EXPECT_GT(r.rows.size(), 0u);
  long points_before = 0;
  for (long at : r.points_taken_at) points_before += at <= R;
  EXPECT_EQ(points_before, 0) << "points were taken while the attempt could still be discarded";
  int warned = 0;
  for (const std::string& w : r.out.warnings)
    warned += w.find("discarded at frame " + std::to_string(R)) != std::string::npos;
  EXPECT_EQ(warned, 1);
  // The poses: none of a frame up to the restart.
  ASSERT_GT(r.out.messages.size(), static_cast<size_t>(R));
  EXPECT_EQ(r.out.messages[R].rfind("restarted", 0), 0u) << r.out.messages[R];
  const nlohmann::json cfg = runConfig("gs_vio");
  auto source = test::contractHost().create<DataSource>(cfg.at("source").at("plugin").get<std::string>(),
                                                        slotParams(cfg, "source"));
  source->open(data);
  EXPECT_GT(t_restart, source->readFrame(static_cast<size_t>(R)).t_ns) << "a frame of the discarded attempt has a pose";
  const StreamedRun off = runStreamed(data, runConfig("gs_vio", {"imu.init_max_imu_chi2=1e-12",
                                                                 "imu.init_restart_refusals=0"}));
  ASSERT_TRUE(off.restart_frames.empty());
  ASSERT_FALSE(off.out.frame_traj.poses.empty());
  EXPECT_LT(off.out.frame_traj.poses.front().t_ns, t_restart);
  int64_t off_rows_before = 0;
  for (const ObservationRow& o : off.rows) off_rows_before += o.frame <= R || o.host <= R;
  EXPECT_GT(off_rows_before, 0);
}

// A failed attempt before the initialisation is begun again: blank images for 8 frames after the start
// lose the tracking (the run fails without the restart); with it the run restarts after the loss,
// starts again once the images are back and initialises.
TEST(VisualInertial, AnAttemptThatFailsBeforeTheInitialisationIsBegunAgain) {
  const std::string data = simDataset("tiny_gs");
  auto blank = [](size_t i, Frame& f) {
    if (i >= 12 && i < 20) f.image.setTo(cv::Scalar::all(128));
  };
  const StreamedRun off = runStreamed(data, runConfig("gs_vio", {"imu.init_restart_refusals=0"}), blank);
  ASSERT_TRUE(off.out.failed) << "the blank frames no longer lose the tracking: this test needs them to";
  const StreamedRun r = runStreamed(data, runConfig("gs_vio", {"imu.init_restart_refusals=20"}), blank);
  ASSERT_FALSE(r.out.failed) << r.out.reason;
  ASSERT_EQ(r.restart_frames.size(), 1u) << r.out.vio.dump();
  EXPECT_NE(r.out.vio.at("start_restarts")[0].at("reason").get<std::string>().find("the attempt failed: tracking lost"),
            std::string::npos) << r.out.vio.dump();
  EXPECT_TRUE(r.out.vio.at("initialised").get<bool>()) << r.out.vio.dump();
  for (const ObservationRow& o : r.rows) ASSERT_GT(o.host, r.restart_frames[0]);
}

TEST(VisualInertial, ADatasetWithoutImuIsRefusedWithTheKey) {
  const std::string data = simDataset("tiny_gs");
  PluginHost& host = test::contractHost();
  const nlohmann::json cfg = runConfig("gs_vio");
  auto source = host.create<DataSource>(cfg.at("source").at("plugin").get<std::string>(), slotParams(cfg, "source"));
  source->open(data);
  SensorSetup s = source->sensors();
  s.has_imu = false;
  try {
    Odometry odo(cfg, host, s);
    FAIL() << "accepted imu.enabled without an IMU";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("imu.enabled"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace rsvio
