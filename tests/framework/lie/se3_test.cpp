// SE3 specifics: the rolling-shutter pose T(t) = exp(xi t) T0 (paper eq. 6) and its Jacobians, the
// camera/IMU twist conversion of paper eqs. 25-31, log at pi from matrices, constructors.
// Shared group properties (exp/log, axioms, eq. 26, Jl/Jr and their inverses): group_properties_test.cpp.
#include <gtest/gtest.h>

#include "framework/lie/lie_test_util.h"
#include "rsvio/lie/lie.h"
#include "support/numeric_jacobian.h"

namespace rsvio {
namespace {

using lie_test::kPi;
using lie_test::Rng;
using Vector6d = Eigen::Matrix<double, 6, 1>;

Vector6d randomTwist(Rng& rng, double max_angle) {
  Vector6d xi;
  xi << lie_test::randomVector(rng, 3.0), lie_test::randomRotationVector(rng, max_angle);
  return xi;
}

TEST(SE3, RollingShutterPoseJacobians) {
  // T(t) = exp(xi t) T0 (eq. 6). With the optimiser's left perturbation of the result:
  //   d T(t) / d xi = t Jl(t xi),  d(T(t) p)/d xi = [I, -[T(t) p]x] t Jl(t xi),  d(T(t) p)/dt = [I, -[y]x] xi.
  Rng rng(200);
  std::vector<Vector6d> twists;
  for (int i = 0; i < lie_test::kJacobianSamples; ++i) twists.push_back(randomTwist(rng, 3.0));
  twists.push_back(Vector6d::Zero());
  twists.push_back((Vector6d() << 1e-12, 0, 0, 0, 1e-13, 0).finished());
  for (const Vector6d& xi : twists) {
    const SE3d T0 = SE3d::sampleUniform(rng);
    const Eigen::Vector3d p = lie_test::randomVector(rng, 5.0);
    const double t = lie_test::uniform(rng, -1.0, 1.0);
    const auto pose = [&](const Vector6d& x) { return SE3d::exp(x * t) * T0; };
    const SE3d Tt = pose(xi);
    const Eigen::Matrix<double, 6, 6> d_T_d_xi = t * SE3d::leftJacobian(t * xi);
    EXPECT_JACOBIAN_NEAR(d_T_d_xi, test::numericJacobian(pose, xi, test::vectorPlus, test::leftMinus<SE3d>, 6), 1e-7);
    const auto point = [&](const Vector6d& x) { return Eigen::Vector3d(pose(x) * p); };
    EXPECT_JACOBIAN_NEAR(Tt.dActionDLeft(p) * d_T_d_xi, test::numericJacobian(point, xi, test::vectorPlus, 6), 1e-7);
    const auto point_t = [&](double s) { return Eigen::Vector3d(SE3d::exp(xi * s) * T0 * p); };
    EXPECT_JACOBIAN_NEAR(Tt.dActionDLeft(p) * xi, test::numericJacobian(point_t, t, test::vectorPlus, 1), 1e-7);
    // And w.r.t. the central pose: left perturbation of T0 enters as Adj(exp(xi t)).
    const auto point_T0 = [&](const SE3d& X) { return Eigen::Vector3d(SE3d::exp(xi * t) * X * p); };
    EXPECT_JACOBIAN_NEAR(Tt.dActionDLeft(p) * SE3d::exp(xi * t).Adj(),
                         test::numericJacobian(point_T0, T0, test::leftPlus<SE3d>, 6), 1e-7);
  }
}

TEST(SE3, RightPerturbationActionJacobian) {
  Rng rng(201);
  for (int i = 0; i < lie_test::kJacobianSamples; ++i) {
    const SE3d T = SE3d::exp(randomTwist(rng, kPi));
    const Eigen::Vector3d p = lie_test::randomVector(rng, 10.0);
    const auto act = [&p](const SE3d& X) { return Eigen::Vector3d(X * p); };
    EXPECT_JACOBIAN_NEAR(T.dActionDRight(p), test::numericJacobian(act, T, test::rightPlus<SE3d>, 6), 1e-7);
    // Left and right perturbations are related by the adjoint: d_right = d_left * Adj.
    EXPECT_LT((T.dActionDRight(p) - T.dActionDLeft(p) * T.Adj()).norm(), 1e-12 * (1 + p.norm()));
  }
}

TEST(SE3, TwistConversionEqs25To31) {
  // xi_cam = -Adj(T_C_I) xi_imu makes T_W_I exp(xi_imu t) = (exp(xi_cam t) T_C_W)^-1 T_C_I (eq. 27-31).
  Rng rng(202);
  for (int i = 0; i < lie_test::kSamples; ++i) {
    const SE3d T_C_I = SE3d::sampleUniform(rng), T_C_W = SE3d::sampleUniform(rng);
    const Vector6d xi_imu = randomTwist(rng, 2.0);
    const double t = lie_test::uniform(rng, -0.05, 0.05);
    const SE3d T_W_I = T_C_W.inverse() * T_C_I;
    const Vector6d xi_cam = -T_C_I.Adj() * xi_imu;
    ASSERT_TRUE((T_W_I * SE3d::exp(xi_imu * t)).isApprox((SE3d::exp(xi_cam * t) * T_C_W).inverse() * T_C_I, 1e-12));
  }
}

TEST(SE3, LogAtPiFromMatrices) {
  const Eigen::Vector3d axis = Eigen::Vector3d(1, 2, -0.5).normalized(), t(0.4, -1.0, 2.0);
  for (double angle : {kPi, kPi - 1e-9, kPi - 1e-6}) {
    const Eigen::Matrix3d R = Eigen::AngleAxisd(angle, axis).toRotationMatrix();
    const SE3d T(R, t);
    const Vector6d xi = T.log();
    EXPECT_NEAR(xi.tail<3>().norm(), angle, 1e-14);
    EXPECT_TRUE(SE3d::exp(xi).isApprox(T, 1e-14)) << angle;
    if (angle < kPi) {
      EXPECT_LT((xi.tail<3>() - angle * axis).norm(), 1e-14);
    }
  }
}

TEST(SE3, ConstructorsAndAccessors) {
  const SO3d R = SO3d::exp(Eigen::Vector3d(0.1, -0.2, 0.3));
  const Eigen::Vector3d t(1, 2, 3);
  const SE3d A(R, t), B(R.matrix(), t), C(R.unit_quaternion(), t), D(A.matrix());
  for (const SE3d& X : {B, C, D}) EXPECT_TRUE(X.isApprox(A, 1e-15));
  EXPECT_EQ(A.translation(), t);
  EXPECT_EQ(A.so3().unit_quaternion().coeffs(), R.unit_quaternion().coeffs());
  EXPECT_EQ(A.params().head<4>(), R.params());
  EXPECT_EQ(A.params().tail<3>(), t);
  EXPECT_EQ(A.matrix3x4(), A.matrix().topRows<3>());
  EXPECT_EQ(SE3d::trans(t) * Eigen::Vector3d::Zero(), t);

  Eigen::Matrix4d M = A.matrix();
  M(3, 0) = 0.5;
  EXPECT_THROW(SE3d{M}, Error);
  EXPECT_THROW(SE3d(Eigen::Matrix3d(2 * Eigen::Matrix3d::Identity()), t), Error);
  EXPECT_THROW(SE3d(Eigen::Quaterniond(0.5, 0, 0, 0), t), Error);
  SE3d X;
  X.setQuaternion(Eigen::Quaterniond(0.5, 0, 0, 0));
  EXPECT_TRUE(X.isApprox(SE3d(), 1e-15));
  X.translation() = t;
  X.setRotationMatrix(R.matrix());
  EXPECT_TRUE(X.isApprox(A, 1e-15));
}

TEST(SE3, FloatJacobians) {
  Rng rng(203);
  using Vector6f = Eigen::Matrix<float, 6, 1>;
  for (int i = 0; i < 200; ++i) {
    const Vector6f xi = randomTwist(rng, 3.0).cast<float>();
    const auto exp = [](const Vector6f& x) { return SE3f::exp(x); };
    EXPECT_JACOBIAN_NEAR(SE3f::leftJacobian(xi),
                         test::numericJacobian(exp, xi, test::vectorPlus, test::leftMinus<SE3f>, 6, 1e-2), 5e-3);
    EXPECT_TRUE(SE3f::exp(SE3f::exp(xi).log()).isApprox(SE3f::exp(xi), 1e-5f));
  }
}

}  // namespace
}  // namespace rsvio
