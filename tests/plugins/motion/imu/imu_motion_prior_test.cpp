// motion.imu: IMU-integrated guesses against the analytic trajectory, the constant-velocity fallback
// before initialisation, the twist prior (eq. 32) against the true camera twist, and loading through
// the plugin host with its parameter table.
#include <gtest/gtest.h>

#include "framework/imu/imu_test_data.h"
#include "plugins/motion/imu/imu_motion_prior.h"
#include "rsvio/config/validate.h"
#include "rsvio/plugin/host.h"
#include "support/numeric_jacobian.h"

namespace rsvio {
namespace {

using test::AnalyticTrajectory;
using test::secToNs;

struct World {
  AnalyticTrajectory tr = AnalyticTrajectory::medium();
  SE3d T_cm_i = test::defaultCameraFromImu();
  RxSO3d T_wm_wf = test::defaultMetricFromFree();
  test::ImuSimOptions o;
  SensorSetup sensors;

  World() {
    o.bias.gyro = Vec3(0.01, -0.02, 0.015);
    o.bias.accel = Vec3(0.1, 0.05, -0.08);
    sensors.has_imu = true;
    sensors.imu = o.noise;
    const SE3d T_b_c = T_cm_i.inverse();
    sensors.camera.T_B_C.linear() = T_b_c.rotationMatrix();
    sensors.camera.T_B_C.translation() = T_b_c.translation();
  }
  void feed(MotionPrior& p, double t0, double t1) const {
    for (const auto& s : test::simulateImu(tr, t0, t1, o)) p.addImu(s);
  }
  MotionState state(double t, bool inertial) const {
    MotionState s;
    s.t_ns = secToNs(t);
    s.T_c_w = test::cameraPoseAt(tr, t, T_cm_i, T_wm_wf);
    s.has_inertial = inertial;
    if (inertial) {
      s.T_wm_wf = SE3d(T_wm_wf.so3(), Vec3::Zero());
      s.scale = T_wm_wf.scale();
      s.v_wm = tr.velocity(t);
      s.bias_gyro = o.bias.gyro;
      s.bias_accel = o.bias.accel;
    }
    return s;
  }
};

TEST(ImuMotionPrior, PredictsTheNextFramePoseFromTheImu) {
  World w;
  ImuMotionPrior p;
  p.setSensors(w.sensors);
  w.feed(p, 0.0, 2.0);
  const std::vector<MotionState> h = {w.state(0.95, true), w.state(1.0, true)};
  for (double t : {1.05, 1.2}) {
    const auto g = p.predict(h, secToNs(t));
    ASSERT_EQ(g.size(), 3u);  // IMU, constant velocity, no motion
    const SE3d truth = test::cameraPoseAt(w.tr, t, w.T_cm_i, w.T_wm_wf);
    const Vec6 err = (g[0] * truth.inverse()).log();
    EXPECT_LT(err.norm(), 1e-5) << "t = " << t;
    // The constant-velocity guess is much worse over a 200 ms gap with this much acceleration.
    if (t > 1.1) EXPECT_GT((g[1] * truth.inverse()).log().norm(), 100 * err.norm());
    ImuState s;
    ASSERT_TRUE(p.predictState(h.back(), secToNs(t), &s));
    EXPECT_LT((s.v_w - w.tr.velocity(t)).norm(), 1e-4);
  }
}

TEST(ImuMotionPrior, FallsBackToConstantVelocityWithoutInertialState) {
  World w;
  ImuMotionPrior p;  // gyro_rotation_guess off (the default)
  p.setSensors(w.sensors);
  w.feed(p, 0.0, 2.0);
  const std::vector<MotionState> h = {w.state(0.95, false), w.state(1.0, false)};
  const auto g = p.predict(h, secToNs(1.05));
  ASSERT_EQ(g.size(), 2u);  // constant velocity, no motion
  const Vec6 v = (h[1].T_c_w * h[0].T_c_w.inverse()).log() / 0.05;
  EXPECT_TRUE(g[0].isApprox(SE3d::exp(v * 0.05) * h[1].T_c_w, 1e-9));
  EXPECT_TRUE(g[1].isApprox(h[1].T_c_w, 1e-12));
  // IMU not covering the requested time: also constant velocity.
  const std::vector<MotionState> hi = {w.state(0.95, true), w.state(1.0, true)};
  EXPECT_EQ(p.predict(hi, secToNs(2.5)).size(), 2u);
  EXPECT_EQ(p.predict({}, secToNs(1.0)).size(), 0u);
}

TEST(ImuMotionPrior, BeforeTheInitialisationTheFirstGuessTurnsWithTheGyroscope) {
  for (bool biased : {false, true}) {
    World w;
    if (!biased) w.o.bias.gyro.setZero();
    ImuMotionOptions opt;
    opt.gyro_rotation_guess = true;
    ImuMotionPrior p(opt);
    p.setSensors(w.sensors);
    w.feed(p, 0.0, 2.0);
    const std::vector<MotionState> h = {w.state(0.95, false), w.state(1.0, false)};
    for (double t : {1.05, 1.2}) {
      const auto g = p.predict(h, secToNs(t));
      ASSERT_EQ(g.size(), 3u) << "t = " << t;  // gyroscope, constant velocity, no motion
      const SE3d truth = test::cameraPoseAt(w.tr, t, w.T_cm_i, w.T_wm_wf);
      const double turn = (h.back().T_c_w.so3() * truth.so3().inverse()).log().norm();
      const double rot_err = (g[0].so3() * truth.so3().inverse()).log().norm();
      // Unbiased: the gyroscope's rotation to the integration's accuracy, against a turn of 0.02-0.07
      // rad. Biased: off by the bias (0.027 rad/s, not estimated before the initialisation) over the gap.
      const double dt = t - 1.0;
      if (biased)
        EXPECT_NEAR(rot_err, w.o.bias.gyro.norm() * dt, 0.1 * w.o.bias.gyro.norm() * dt) << "t = " << t;
      else
        EXPECT_LT(rot_err, 1e-3 * turn) << "t = " << t << ", turn " << turn;
      // Translation: the constant-velocity guess's camera centre.
      EXPECT_LT((g[0].inverse().translation() - g[1].inverse().translation()).norm(), 1e-12);
    }
    // No IMU data there: constant velocity first.
    EXPECT_EQ(p.predict(h, secToNs(2.5)).size(), 2u);
  }
}

TEST(ImuMotionPrior, TwistPriorIsTheTrueCameraTwistWithParamInformation) {
  World w;
  ImuMotionOptions opt;
  opt.twist_sigma_trans_m_s = 0.2;
  opt.twist_sigma_rot_rad_s = 0.05;
  ImuMotionPrior p(opt);
  p.setSensors(w.sensors);
  w.feed(p, 0.0, 2.0);
  const double t = 1.2345;
  TwistPrior prior;
  ASSERT_TRUE(p.twistPrior({}, w.state(t, true), &prior));
  const auto xi_true = test::numericJacobian(
      [&](double tau) { return test::cameraPoseAt(w.tr, t + tau, w.T_cm_i, w.T_wm_wf); }, 0.0, test::vectorPlus,
      test::leftMinus<SE3d>, 1, 1e-5);
  // The gyroscope is interpolated between 200 Hz samples at the keyframe time: ~1e-5 rad/s.
  EXPECT_LT((prior.mean - Vec6(xi_true)).norm(), 1e-4) << prior.mean.transpose() << "\n" << xi_true.transpose();
  const double s = w.T_wm_wf.scale();
  EXPECT_NEAR(prior.information(0, 0), s * s / (0.2 * 0.2), 1e-9);
  EXPECT_NEAR(prior.information(5, 5), 1.0 / (0.05 * 0.05), 1e-9);
  EXPECT_EQ(prior.information(0, 1), 0.0);
  EXPECT_FALSE(p.twistPrior({}, w.state(t, false), &prior));
  EXPECT_FALSE(p.twistPrior({}, w.state(5.0, true), &prior));  // no IMU data there
}

TEST(ImuMotionPrior, LoadsThroughTheHostWithItsParamTable) {
  PluginHost host({RSVIO_PLUGIN_DIR});
  const PluginInfo& info = host.info("motion.imu");
  EXPECT_EQ(info.kind, PluginKind::Motion);
  std::vector<ConfigProblem> problems;
  const auto params = validateParams(nlohmann::json{{"recovery", false}}, info.params, "motion.imu.params", problems);
  ASSERT_TRUE(problems.empty());
  EXPECT_DOUBLE_EQ(params["twist_sigma_trans_m_s"].get<double>(), 0.1);
  auto prior = host.create<MotionPrior>("motion.imu", Params(params));
  World w;
  prior->setSensors(w.sensors);
  w.feed(*prior, 0.0, 1.5);
  const auto g = prior->predict({w.state(0.95, true), w.state(1.0, true)}, secToNs(1.1));
  ASSERT_EQ(g.size(), 1u);  // recovery off: the IMU guess only
  EXPECT_LT((g[0] * test::cameraPoseAt(w.tr, 1.1, w.T_cm_i, w.T_wm_wf).inverse()).log().norm(), 1e-5);
  // gyro_rotation_guess reaches the plugin: before the initialisation a third guess comes first.
  auto gyro = host.create<MotionPrior>(
      "motion.imu", Params(validateParams(nlohmann::json{{"gyro_rotation_guess", true}}, info.params,
                                          "motion.imu.params", problems)));
  ASSERT_TRUE(problems.empty());
  gyro->setSensors(w.sensors);
  w.feed(*gyro, 0.0, 1.5);
  EXPECT_EQ(gyro->predict({w.state(0.95, false), w.state(1.0, false)}, secToNs(1.1)).size(), 3u);
  problems.clear();
  validateParams(nlohmann::json{{"twist_sigma_rot_rad_s", -1.0}}, info.params, "motion.imu.params", problems);
  EXPECT_EQ(problems.size(), 1u);
}

// The window's smooth-motion prior on rolling-shutter twists: on by default (a rolling shutter added to
// a visual-inertial config holds its twists before the initialisation without a second motion slot),
// its information from the params, none with both weights 0.
TEST(ImuMotionPrior, HandsTheSmoothMotionInformationToTheBackEnd) {
  Mat6 info;
  ASSERT_TRUE(ImuMotionPrior().smoothMotionInformation(&info));
  EXPECT_DOUBLE_EQ(info(0, 0), 1e5);
  EXPECT_DOUBLE_EQ(info(5, 5), 1e5);
  ImuMotionOptions o;
  o.smooth_twist_info_trans = 10.0;
  o.smooth_twist_info_rot = 100.0;
  ASSERT_TRUE(ImuMotionPrior(o).smoothMotionInformation(&info));
  EXPECT_DOUBLE_EQ(info(2, 2), 10.0);
  EXPECT_DOUBLE_EQ(info(3, 3), 100.0);
  EXPECT_DOUBLE_EQ(info(0, 3), 0.0);
  o.smooth_twist_info_trans = o.smooth_twist_info_rot = 0.0;
  EXPECT_FALSE(ImuMotionPrior(o).smoothMotionInformation(&info));
  PluginHost host({RSVIO_PLUGIN_DIR});
  std::vector<ConfigProblem> problems;
  const auto params = validateParams(nlohmann::json{{"smooth_twist_info_rot", 7.0}}, host.info("motion.imu").params,
                                     "motion.imu.params", problems);
  ASSERT_TRUE(problems.empty());
  ASSERT_TRUE(host.create<MotionPrior>("motion.imu", Params(params))->smoothMotionInformation(&info));
  EXPECT_DOUBLE_EQ(info(0, 0), 1e5);
  EXPECT_DOUBLE_EQ(info(4, 4), 7.0);
}

}  // namespace
}  // namespace rsvio
