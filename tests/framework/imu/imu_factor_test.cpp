// IMU factor (imu_factor.h), the Fig. 3 frame chain (imu_frames.h) and the factor as seen by the
// photometric BA (visual_inertial_factor.h): truth gives zero residuals, every Jacobian matches numeric
// differences at random non-trivial states, and a Gauss-Newton over several factors recovers biases.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>

#include "framework/imu/imu_test_data.h"
#include "rsvio/imu/imu_factor.h"
#include "rsvio/imu/visual_inertial_factor.h"
#include "support/numeric_jacobian.h"

namespace rsvio {
namespace {

using test::AnalyticTrajectory;
using test::numericJacobian;
using test::secToNs;

ImuBuffer bufferOf(const std::vector<ImuSample>& samples) {
  ImuBuffer b;
  for (const auto& s : samples) b.add(s);
  return b;
}

Vec3 randomVec(std::mt19937_64& rng, double scale) {
  std::normal_distribution<double> n(0.0, scale);
  return Vec3(n(rng), n(rng), n(rng));
}

ImuState perturbed(const ImuState& s, std::mt19937_64& rng) {
  ImuState r = s;
  r.R_w_i = SO3d::exp(randomVec(rng, 0.1)) * s.R_w_i;
  r.p_w_i += randomVec(rng, 0.1);
  r.v_w += randomVec(rng, 0.2);
  r.bias.gyro += randomVec(rng, 0.01);
  r.bias.accel += randomVec(rng, 0.05);
  return r;
}

// Forster's right chart on the pose part (d_phi, d_p): the rows of ImuPoseJacobians.
Eigen::VectorXd poseRightMinus(const SE3d& T, const SE3d& T0) {
  Eigen::VectorXd d(6);
  d.head<3>() = (T0.so3().inverse() * T.so3()).log();
  d.tail<3>() = T0.so3().inverse() * Vec3(T.translation() - T0.translation());
  return d;
}

struct Fixture {
  AnalyticTrajectory tr = AnalyticTrajectory::medium();
  test::ImuSimOptions o;
  ImuBias bias_lin;
  double ti = 0.61234, tj = 1.1;
  ImuFactor factor;
  Fixture() {
    bias_lin.gyro = Vec3(0.01, -0.02, 0.005);
    bias_lin.accel = Vec3(0.05, 0.02, -0.1);
    o.bias = bias_lin;
    const ImuBuffer buf = bufferOf(test::simulateImu(tr, 0.0, 2.0, o));
    factor = ImuFactor(ImuPreintegration::fromBuffer(buf, secToNs(ti), secToNs(tj), o.noise, bias_lin, 0.0));
  }
};

TEST(ImuFactor, ZeroResidualAtTruth) {
  Fixture f;
  const Vec15 r = f.factor.residual(f.tr.state(f.ti, f.bias_lin), f.tr.state(f.tj, f.bias_lin));
  EXPECT_LT(r.segment<3>(kResRot).norm(), 2e-6);
  EXPECT_LT(r.segment<3>(kResVel).norm(), 5e-5);
  EXPECT_LT(r.segment<3>(kResPos).norm(), 5e-5);
  EXPECT_EQ(r.tail<6>().norm(), 0.0);
}

TEST(ImuFactor, PredictStateReachesTheNextStateAndZeroesTheResidual) {
  Fixture f;
  const ImuState si = f.tr.state(f.ti, f.bias_lin);
  const ImuState pred = predictState(si, f.factor.preintegration());
  const ImuState truth = f.tr.state(f.tj, f.bias_lin);
  EXPECT_LT((pred.R_w_i.inverse() * truth.R_w_i).log().norm(), 2e-6);
  EXPECT_LT((pred.v_w - truth.v_w).norm(), 5e-5);
  EXPECT_LT((pred.p_w_i - truth.p_w_i).norm(), 5e-5);
  EXPECT_LT(f.factor.residual(si, pred).norm(), 1e-12);  // eqs. 13-15 are what eqs. 16-19 compare against
}

TEST(ImuFactor, JacobiansMatchNumeric) {
  Fixture f;
  std::mt19937_64 rng(3);
  const auto plus = [](const ImuState& x, const Eigen::VectorXd& d) { return boxPlus(x, Vec15(d)); };
  for (int trial = 0; trial < 5; ++trial) {
    const ImuState si = perturbed(f.tr.state(f.ti, f.bias_lin), rng);
    const ImuState sj = perturbed(f.tr.state(f.tj, f.bias_lin), rng);
    const double offset = 0.003 * (trial - 2);  // away from the linearisation offset 0
    ImuFactorJacobians J;
    f.factor.residual(si, sj, offset, &J);
    const auto num_i = numericJacobian([&](const ImuState& x) { return f.factor.residual(x, sj, offset); }, si, plus, 15);
    const auto num_j = numericJacobian([&](const ImuState& x) { return f.factor.residual(si, x, offset); }, sj, plus, 15);
    const auto num_o = numericJacobian([&](double o) { return f.factor.residual(si, sj, o); }, offset, test::vectorPlus, 1);
    EXPECT_JACOBIAN_NEAR(J.d_res_d_state_i, num_i, 1e-6) << "trial " << trial;
    EXPECT_JACOBIAN_NEAR(J.d_res_d_state_j, num_j, 1e-6) << "trial " << trial;
    EXPECT_JACOBIAN_NEAR(J.d_res_d_offset, num_o, 1e-6) << "trial " << trial;
  }
}

TEST(ImuFactor, InformationIsInverseCovarianceAndWhitens) {
  Fixture f;
  const Mat15 I = f.factor.information() * f.factor.preintegration().fullCovariance();
  EXPECT_LT((I - Mat15::Identity()).norm(), 1e-6);
  const Mat15 U = f.factor.sqrtInformation();
  EXPECT_LT((U.transpose() * U - f.factor.information()).norm() / f.factor.information().norm(), 1e-9);
}

TEST(ImuFrames, MetricPoseChainRoundTripsAndMatchesFig3) {
  const SE3d T_cm_i = test::defaultCameraFromImu();
  const RxSO3d T_wm_wf = test::defaultMetricFromFree();
  const SE3d T_wm_i(SO3d::exp(Vec3(0.4, -1.0, 2.0)), Vec3(1.0, -2.0, 0.5));
  const SE3d T_cf_wf = cameraPoseFromImu(T_wm_i, T_wm_wf, T_cm_i);
  EXPECT_TRUE(imuPoseFromCamera(T_cf_wf, T_wm_wf, T_cm_i).isApprox(T_wm_i, 1e-9));
  // As similarity transforms: T_Wm_I = T_Wm_Wf T_Wf_Cf T_Cf_Cm T_Cm_I with T_Cf_Cm = (1/s, I).
  const Vec3 p_i(0.3, -0.7, 1.9);
  const Vec3 p_cm = T_cm_i * p_i;
  const Vec3 p_wf = T_cf_wf.inverse() * Vec3(p_cm / T_wm_wf.scale());
  EXPECT_LT((T_wm_wf * p_wf - T_wm_i * p_i).norm(), 1e-12);
  // The metric camera pose is rigid with the camera centre scaled.
  const SE3d T_cm_wm = metricCameraPose(T_cf_wf, T_wm_wf);
  EXPECT_LT((T_cm_wm.inverse().translation() - T_wm_wf * Vec3(T_cf_wf.inverse().translation())).norm(), 1e-12);
}

TEST(ImuFrames, JacobiansMatchNumeric) {
  const SE3d T_cm_i = test::defaultCameraFromImu();
  std::mt19937_64 rng(11);
  for (int trial = 0; trial < 5; ++trial) {
    const RxSO3d T_wm_wf(std::exp(randomVec(rng, 1.0).x()), SO3d::sampleUniform(rng));
    const SE3d T_cf_wf(SO3d::sampleUniform(rng), randomVec(rng, 2.0));
    ImuPoseJacobians J;
    const SE3d T0 = imuPoseFromCamera(T_cf_wf, T_wm_wf, T_cm_i, &J);
    const auto num_c = numericJacobian([&](const SE3d& T) { return imuPoseFromCamera(T, T_wm_wf, T_cm_i); }, T_cf_wf,
                                       test::leftPlus<SE3d>, poseRightMinus, 6);
    const auto num_w = numericJacobian([&](const RxSO3d& S) { return imuPoseFromCamera(T_cf_wf, S, T_cm_i); }, T_wm_wf,
                                       test::leftPlus<RxSO3d>, poseRightMinus, 4);
    EXPECT_JACOBIAN_NEAR(J.d_pose_d_T_cf_wf, num_c, 1e-6);
    EXPECT_JACOBIAN_NEAR(J.d_pose_d_T_wm_wf, num_w, 1e-6);
    (void)T0;
  }
}

TEST(VisualInertialFactor, ResidualAtTruthAndJacobiansMatchNumeric) {
  Fixture f;
  const SE3d T_cm_i = test::defaultCameraFromImu();
  const RxSO3d T_wm_wf = test::defaultMetricFromFree();
  VisualInertialKeyframe ki, kj;
  ki.T_cf_wf = test::cameraPoseAt(f.tr, f.ti, T_cm_i, T_wm_wf);
  kj.T_cf_wf = test::cameraPoseAt(f.tr, f.tj, T_cm_i, T_wm_wf);
  ki.v_wm = f.tr.velocity(f.ti);
  kj.v_wm = f.tr.velocity(f.tj);
  ki.bias = kj.bias = f.bias_lin;
  const Vec15 r0 = visualInertialResidual(f.factor, ki, kj, T_wm_wf, T_cm_i, 0.0);
  EXPECT_LT(r0.norm(), 1e-4);

  std::mt19937_64 rng(5);
  for (int trial = 0; trial < 5; ++trial) {
    VisualInertialKeyframe a = ki, b = kj;
    a.T_cf_wf = SE3d::exp((Vec6() << randomVec(rng, 0.05), randomVec(rng, 0.1)).finished()) * a.T_cf_wf;
    b.T_cf_wf = SE3d::exp((Vec6() << randomVec(rng, 0.05), randomVec(rng, 0.1)).finished()) * b.T_cf_wf;
    a.v_wm += randomVec(rng, 0.3);
    b.bias.gyro += randomVec(rng, 0.01);
    a.bias.accel += randomVec(rng, 0.05);
    const RxSO3d S = RxSO3d::exp((Vec4() << randomVec(rng, 0.1), 0.2).finished()) * T_wm_wf;
    const double off = 0.004;
    VisualInertialJacobians J;
    visualInertialResidual(f.factor, a, b, S, T_cm_i, off, &J);
    auto res = [&](const VisualInertialKeyframe& x, const VisualInertialKeyframe& y, const RxSO3d& s, double o) {
      return visualInertialResidual(f.factor, x, y, s, T_cm_i, o);
    };
    const auto velBiasPlus = [](const VisualInertialKeyframe& k, const Eigen::VectorXd& d) {
      VisualInertialKeyframe r = k;
      r.v_wm += d.segment<3>(0);
      r.bias.gyro += d.segment<3>(3);
      r.bias.accel += d.segment<3>(6);
      return r;
    };
    const auto posePlus = [](const VisualInertialKeyframe& k, const Eigen::VectorXd& d) {
      VisualInertialKeyframe r = k;
      r.T_cf_wf = SE3d::exp(Vec6(d)) * k.T_cf_wf;
      return r;
    };
    EXPECT_JACOBIAN_NEAR(J.d_res_d_T_cf_wf_i, numericJacobian([&](const auto& x) { return res(x, b, S, off); }, a, posePlus, 6), 1e-6);
    EXPECT_JACOBIAN_NEAR(J.d_res_d_T_cf_wf_j, numericJacobian([&](const auto& x) { return res(a, x, S, off); }, b, posePlus, 6), 1e-6);
    EXPECT_JACOBIAN_NEAR(J.d_res_d_vel_bias_i, numericJacobian([&](const auto& x) { return res(x, b, S, off); }, a, velBiasPlus, 9), 1e-6);
    EXPECT_JACOBIAN_NEAR(J.d_res_d_vel_bias_j, numericJacobian([&](const auto& x) { return res(a, x, S, off); }, b, velBiasPlus, 9), 1e-6);
    EXPECT_JACOBIAN_NEAR(J.d_res_d_T_wm_wf, numericJacobian([&](const RxSO3d& x) { return res(a, b, x, off); }, S, test::leftPlus<RxSO3d>, 4), 1e-6);
    EXPECT_JACOBIAN_NEAR(J.d_res_d_offset, numericJacobian([&](double o) { return res(a, b, S, o); }, off, test::vectorPlus, 1), 1e-6);
  }
}

// Constant biases are recovered by Gauss-Newton over several IMU factors: poses known (as from vision),
// velocities and per-keyframe biases unknown, noisy IMU at consumer-grade densities.
TEST(ImuFactor, GaussNewtonRecoversConstantBiases) {
  const AnalyticTrajectory tr = AnalyticTrajectory::medium();
  test::ImuSimOptions o;
  o.add_noise = true;
  o.bias.gyro = Vec3(0.012, -0.021, 0.017);
  o.bias.accel = Vec3(0.15, -0.08, 0.11);
  std::mt19937_64 rng(21);
  const ImuBuffer buf = bufferOf(test::simulateImu(tr, 0.0, 6.5, o, &rng));
  const int n = 13;  // keyframes every 0.5 s
  std::vector<double> t(n);
  std::vector<ImuFactor> factors;
  std::vector<ImuState> x(n);
  for (int k = 0; k < n; ++k) {
    t[k] = 0.1 + 0.5 * k;
    x[k] = tr.state(t[k]);  // zero bias, true pose, velocity disturbed
    x[k].v_w += Vec3(0.2, -0.1, 0.1);
  }
  for (int k = 0; k + 1 < n; ++k)
    factors.emplace_back(ImuPreintegration::fromBuffer(buf, secToNs(t[k]), secToNs(t[k + 1]), o.noise, ImuBias{}));
  // Unknowns per keyframe: (v, bg, ba); poses fixed.
  const int dim = 9 * n;
  for (int it = 0; it < 5; ++it) {
    Eigen::MatrixXd H = Eigen::MatrixXd::Zero(dim, dim);
    Eigen::VectorXd g = Eigen::VectorXd::Zero(dim);
    for (int k = 0; k + 1 < n; ++k) {
      ImuFactorJacobians J;
      const Vec15 r = factors[k].residual(x[k], x[k + 1], &J);
      Eigen::Matrix<double, 15, 18> A;
      A << J.d_res_d_state_i.middleCols<9>(kStateVel), J.d_res_d_state_j.middleCols<9>(kStateVel);
      const Mat15 W = factors[k].information();
      H.block<18, 18>(9 * k, 9 * k) += A.transpose() * W * A;
      g.segment<18>(9 * k) += A.transpose() * W * r;
    }
    const Eigen::VectorXd dx = H.ldlt().solve(-g);
    for (int k = 0; k < n; ++k) {
      x[k].v_w += dx.segment<3>(9 * k);
      x[k].bias.gyro += dx.segment<3>(9 * k + 3);
      x[k].bias.accel += dx.segment<3>(9 * k + 6);
    }
  }
  Vec3 bg = Vec3::Zero(), ba = Vec3::Zero();
  for (const auto& s : x) {
    bg += s.bias.gyro / n;
    ba += s.bias.accel / n;
  }
  std::printf("bias recovery: gyro error %.2e rad/s, accel error %.2e m/s^2\n", (bg - o.bias.gyro).norm(),
              (ba - o.bias.accel).norm());
  EXPECT_LT((bg - o.bias.gyro).norm(), 1e-3);   // true |b_g| = 0.03 rad/s
  EXPECT_LT((ba - o.bias.accel).norm(), 2e-2);  // true |b_a| = 0.2 m/s^2
  for (int k = 0; k < n; ++k) EXPECT_LT((x[k].v_w - tr.velocity(t[k])).norm(), 2e-2) << k;
}

}  // namespace
}  // namespace rsvio
