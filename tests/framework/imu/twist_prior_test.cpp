// Twist prior and twist energy residual (twist_prior.h, paper eqs. 22-33).
#include <gtest/gtest.h>

#include <random>

#include "framework/imu/imu_test_data.h"
#include "rsvio/imu/twist_prior.h"
#include "support/numeric_jacobian.h"

namespace rsvio {
namespace {

using test::AnalyticTrajectory;
using test::numericJacobian;

// At the true state the prior equals the camera's true twist per second in W_f units, defined by
// T_Cf_Wf(t + tau) = exp(xi tau) T_Cf_Wf(t) (paper eq. 6): the signs of eq. 25 and the division by the
// scale in eq. 32 are checked against the trajectory itself, with a non-identity extrinsic.
TEST(TwistPrior, EqualsTrueCameraTwist) {
  const AnalyticTrajectory tr = AnalyticTrajectory::medium();
  const SE3d T_cm_i = test::defaultCameraFromImu();
  const RxSO3d T_wm_wf = test::defaultMetricFromFree();
  const Vec3 bg(0.01, -0.02, 0.03);
  for (double t : {0.3, 1.1, 2.7}) {
    const SE3d T0 = test::cameraPoseAt(tr, t, T_cm_i, T_wm_wf);
    const auto xi_true = numericJacobian([&](double tau) { return test::cameraPoseAt(tr, t + tau, T_cm_i, T_wm_wf); },
                                         0.0, test::vectorPlus, test::leftMinus<SE3d>, 1, 1e-5);
    const Vec6 prior = imuTwistPrior(tr.angularVelocityBody(t) + bg, tr.velocity(t), bg, T0, T_wm_wf, T_cm_i);
    EXPECT_LT((prior - Vec6(xi_true)).norm(), 1e-7 * (1.0 + prior.norm())) << "t = " << t << "\nprior "
                                                                          << prior.transpose() << "\ntrue  "
                                                                          << xi_true.transpose();
    EXPECT_GT(prior.head<3>().norm(), 0.1);  // moving: the test is not vacuous
  }
}

// A later frame's twist from a keyframe's state (imuFrameTwist: what the tracker holds in rs_vio) is the
// frame's own true twist: the gyroscope at the frame's time and the velocity propagated to it, not the
// keyframe's. Noise-free 200 Hz IMU with a gyro bias, a non-identity extrinsic and time offset, the
// frame 72.5 ms after the keyframe (between two samples). Shown once: the gyroscope taken at the
// keyframe's time misses by 0.039-0.046 rad/s, the keyframe's velocity unpropagated by 0.11-0.21 m/s.
TEST(TwistPrior, FrameTwistFromAKeyframeStateIsTheFramesTrueTwist) {
  const AnalyticTrajectory tr = AnalyticTrajectory::medium();
  const SE3d T_cm_i = test::defaultCameraFromImu();
  const RxSO3d T_wm_wf = test::defaultMetricFromFree();
  const double offset_s = 0.004;  // t_imu = t_cam + offset
  ImuBias bias;
  bias.gyro = Vec3(0.01, -0.02, 0.03);
  bias.accel = Vec3(0.05, 0.02, -0.04);
  test::ImuSimOptions so;
  so.bias = bias;
  ImuBuffer buffer;
  for (const ImuSample& s : test::simulateImu(tr, 0.0, 4.0, so)) buffer.add(s);
  ImuNoise noise;
  for (double t_kf : {0.6, 1.35, 2.9}) {  // camera times; the IMU is at t + offset
    const double t = t_kf + 0.0725;
    const ImuState from = tr.state(t_kf + offset_s, bias);
    const SE3d T_frame = test::cameraPoseAt(tr, t + offset_s, T_cm_i, T_wm_wf);
    Vec6 xi = Vec6::Zero();
    ASSERT_TRUE(imuFrameTwist(buffer, noise, from, test::secToNs(t_kf), test::secToNs(t), offset_s, T_frame, T_wm_wf,
                              T_cm_i, &xi));
    const auto xi_true = numericJacobian(
        [&](double tau) { return test::cameraPoseAt(tr, t + offset_s + tau, T_cm_i, T_wm_wf); }, 0.0,
        test::vectorPlus, test::leftMinus<SE3d>, 1, 1e-5);
    const Vec6 d = xi - Vec6(xi_true);
    // Translation in W_f units per second (2.5 m each): 2 mm/s; rotation 1 mrad/s.
    EXPECT_LT(d.head<3>().norm() * T_wm_wf.scale(), 2e-3) << "t " << t << "\nimu  " << xi.transpose() << "\ntrue "
                                                          << xi_true.transpose();
    EXPECT_LT(d.tail<3>().norm(), 1e-3) << "t " << t << "\nimu  " << xi.transpose() << "\ntrue " << xi_true.transpose();
  }
  // No IMU data up to the frame: no twist.
  Vec6 xi = Vec6::Constant(7.0);
  EXPECT_FALSE(imuFrameTwist(buffer, noise, tr.state(3.9, bias), test::secToNs(3.9), test::secToNs(4.2), 0.0,
                             SE3d(), T_wm_wf, T_cm_i, &xi));
  EXPECT_EQ(xi, Vec6::Constant(7.0));
}

TEST(TwistPrior, JacobiansMatchNumeric) {
  const SE3d T_cm_i = test::defaultCameraFromImu();
  std::mt19937_64 rng(17);
  std::normal_distribution<double> n(0.0, 1.0);
  auto vec3 = [&](double s) { return Vec3(s * n(rng), s * n(rng), s * n(rng)); };
  for (int trial = 0; trial < 5; ++trial) {
    const RxSO3d S(std::exp(n(rng)), SO3d::sampleUniform(rng));
    const SE3d T(SO3d::sampleUniform(rng), vec3(2.0));
    const Vec3 w = vec3(1.0), v = vec3(1.5), bg = vec3(0.05);
    Vec6 xi;
    xi << vec3(0.5), vec3(1.0);
    TwistPriorJacobians J;
    twistResidual(xi, w, v, bg, T, S, T_cm_i, &J);
    auto res = [&](const Vec6& x, const Vec3& vv, const Vec3& b, const SE3d& TT, const RxSO3d& SS) {
      return twistResidual(x, w, vv, b, TT, SS, T_cm_i);
    };
    EXPECT_JACOBIAN_NEAR(J.d_res_d_v, numericJacobian([&](const Vec3& x) { return res(xi, x, bg, T, S); }, v, test::vectorPlus, 3), 1e-6);
    EXPECT_JACOBIAN_NEAR(J.d_res_d_bg, numericJacobian([&](const Vec3& x) { return res(xi, v, x, T, S); }, bg, test::vectorPlus, 3), 1e-6);
    EXPECT_JACOBIAN_NEAR(J.d_res_d_T_cf_wf, numericJacobian([&](const SE3d& x) { return res(xi, v, bg, x, S); }, T, test::leftPlus<SE3d>, 6), 1e-6);
    EXPECT_JACOBIAN_NEAR(J.d_res_d_T_wm_wf, numericJacobian([&](const RxSO3d& x) { return res(xi, v, bg, T, x); }, S, test::leftPlus<RxSO3d>, 4), 1e-6);
    EXPECT_JACOBIAN_NEAR(J.d_res_d_twist, numericJacobian([&](const Vec6& x) { return res(x, v, bg, T, S); }, xi, test::vectorPlus, 6), 1e-6);
  }
}

}  // namespace
}  // namespace rsvio
