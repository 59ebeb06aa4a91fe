// RxSO3 and Sim3 specifics: eq. 2's 4x4 form, tiny and huge scales, the Sim3 W matrix across its
// series/closed-form switch, constructors. Shared properties: group_properties_test.cpp.
#include <gtest/gtest.h>

#include <unsupported/Eigen/MatrixFunctions>

#include "framework/lie/lie_test_util.h"
#include "rsvio/lie/lie.h"
#include "support/numeric_jacobian.h"

namespace rsvio {
namespace {

using lie_test::kPi;
using lie_test::Rng;
using Vector7d = Eigen::Matrix<double, 7, 1>;

TEST(RxSO3, ActsAsEq2AndSplitsIntoScaleAndRotation) {
  Rng rng(300);
  for (int i = 0; i < lie_test::kSamples; ++i) {
    const RxSO3d X = RxSO3d::sampleUniform(rng);
    const Eigen::Vector3d p = lie_test::randomVector(rng, 10.0);
    Eigen::Matrix4d eq2 = Eigen::Matrix4d::Identity();
    eq2.topLeftCorner<3, 3>() = X.scale() * X.rotationMatrix();
    ASSERT_EQ(X.matrix4(), eq2);
    ASSERT_LT((X * p - X.scale() * (X.so3() * p)).norm(), 1e-13 * (1 + p.norm()));
    ASSERT_NEAR(X.log()[3], std::log(X.scale()), 1e-15);
    ASSERT_LT((X.log().head<3>() - X.so3().log()).norm(), 1e-15);
    ASSERT_TRUE(RxSO3d(X.matrix()).isApprox(X, 1e-14));
  }
}

TEST(RxSO3, TinyAndHugeScales) {
  for (double s : {1e-300, 1e-12, 1e-6, 1.0, 1e6, 1e12, 1e300}) {
    const RxSO3d X(s, SO3d::rotY(kPi - 1e-9));
    // sigma = log(s) carries an absolute error of ~eps * |sigma| (690 at s = 1e300).
    EXPECT_TRUE(RxSO3d::exp(X.log()).isApprox(X, 1e-12)) << s;
    EXPECT_NEAR((X * X.inverse()).scale(), 1.0, 1e-15);
    EXPECT_DOUBLE_EQ(X.inverse().scale(), 1.0 / s);
  }
}

TEST(RxSO3, ConstructorsCheckScale) {
  EXPECT_THROW(RxSO3d(0.0, SO3d()), Error);
  EXPECT_THROW(RxSO3d(-1.0, SO3d()), Error);
  EXPECT_THROW(RxSO3d(std::nan(""), SO3d()), Error);
  EXPECT_THROW(RxSO3d(std::numeric_limits<double>::infinity(), SO3d()), Error);
  EXPECT_THROW(RxSO3d(Eigen::Matrix3d(-2.0 * Eigen::Matrix3d::Identity())), Error);  // det < 0
  EXPECT_THROW(RxSO3d(Eigen::Matrix3d(Eigen::Vector3d(1, 2, 3).asDiagonal())), Error);
  RxSO3d X;
  EXPECT_THROW(X.setScale(0.0), Error);
  X.setScale(3.0);
  EXPECT_EQ(X.scale(), 3.0);
  const RxSO3d Y(2.0, Eigen::Quaterniond(SO3d::rotZ(0.5).unit_quaternion()));
  EXPECT_EQ(Y.params()[4], 2.0);
  EXPECT_TRUE(Y.so3().isApprox(SO3d::rotZ(0.5), 1e-15));
}

TEST(Sim3, WContinuousAcrossSeriesSwitch) {
  // calcW switches from the double series to closed forms at |(theta, sigma)| = 1 and to the
  // theta -> 0 limits at theta = epsilon; both sides must agree (and with the matrix exponential).
  Rng rng(301);
  for (int i = 0; i < lie_test::kSamples; ++i) {
    const Eigen::Vector3d axis = lie_test::randomUnit(rng);
    const double phi = lie_test::uniform(rng, 0.0, 2 * kPi);
    const double theta = std::abs(std::cos(phi)), sigma = std::sin(phi);  // on the unit circle
    const Eigen::Matrix3d below = Sim3d::calcW(axis * theta * (1 - 1e-15), sigma * (1 - 1e-15));
    const Eigen::Matrix3d above = Sim3d::calcW(axis * theta * (1 + 1e-15), sigma * (1 + 1e-15));
    ASSERT_LT((below - above).cwiseAbs().maxCoeff(), 1e-14) << theta << " " << sigma;
  }
  for (double sigma : {-30.0, -5.0, -1.0, 1.0, 5.0, 30.0}) {
    const double eps = lie::Constants<double>::epsilon();
    const Eigen::Vector3d axis = Eigen::Vector3d(0.2, 0.3, -1).normalized();
    const Eigen::Matrix3d below = Sim3d::calcW(axis * eps * (1 - 1e-12), sigma);
    const Eigen::Matrix3d above = Sim3d::calcW(axis * eps * (1 + 1e-12), sigma);
    EXPECT_LT((below - above).cwiseAbs().maxCoeff() / below.norm(), 1e-14) << sigma;
  }
}

TEST(Sim3, WIsIntegralOfExp) {
  // W upsilon is the translation of exp, i.e. the top-right block of the 4x4 matrix exponential.
  Rng rng(302);
  for (int i = 0; i < lie_test::kSamples; ++i) {
    const Eigen::Vector3d w = lie_test::randomRotationVector(rng, kPi);
    const double sigma = lie_test::uniform(rng, -10.0, 10.0) * (i % 2 ? 1.0 : 1e-3);
    Eigen::Matrix4d X = Eigen::Matrix4d::Zero();
    X.topLeftCorner<3, 3>() = SO3d::hat(w) + sigma * Eigen::Matrix3d::Identity();
    for (int c = 0; c < 3; ++c) {
      X.topRightCorner<3, 1>() = Eigen::Vector3d::Unit(c);
      const Eigen::Vector3d expected = X.exp().topRightCorner<3, 1>();
      ASSERT_LT((Sim3d::calcW(w, sigma).col(c) - expected).norm(), 1e-13 * std::max(1.0, expected.norm()));
    }
  }
}

TEST(Sim3, TinyScalesAndLargeTranslations) {
  Rng rng(303);
  for (double sigma : {-40.0, -25.0, -1e-12, 0.0, 1e-300, 25.0}) {
    for (double angle : {0.0, 1e-12, 1.0, kPi - 1e-9, kPi}) {
      Vector7d a;
      a << 1e3, -2e2, 5.0, lie_test::randomUnit(rng) * angle, sigma;
      const Sim3d T = Sim3d::exp(a);
      EXPECT_TRUE(Sim3d::exp(T.log()).isApprox(T, 1e-12)) << sigma << " " << angle;
      if (angle < kPi) {
        EXPECT_LT((T.log() - a).norm(), 1e-9 * a.norm()) << sigma << " " << angle;
      }
      // T T^-1 = I up to rounding relative to |t| (3e12 at sigma = 25).
      const Sim3d I = T * T.inverse();
      EXPECT_TRUE(I.rxso3().isApprox(RxSO3d(), 1e-14));
      EXPECT_LT(I.translation().norm(), 1e-14 * std::max(1.0, T.translation().norm()));
    }
  }
}

TEST(Sim3, ConstructorsAndAccessors) {
  const RxSO3d sR(2.5, SO3d::rotX(0.7));
  const Eigen::Vector3d t(1, -2, 3);
  const Sim3d A(sR, t), B(sR.matrix(), t), C(2.5, sR.unit_quaternion(), t), D(A.matrix());
  for (const Sim3d& X : {B, C, D}) EXPECT_TRUE(X.isApprox(A, 1e-14));
  EXPECT_EQ(A.scale(), 2.5);
  EXPECT_EQ(A.translation(), t);
  EXPECT_EQ(A.params().segment<5>(0), sR.params());
  EXPECT_EQ(A.params().tail<3>(), t);
  EXPECT_TRUE(A.so3().isApprox(SO3d::rotX(0.7), 1e-15));
  EXPECT_EQ(A.matrix3x4(), A.matrix().topRows<3>());
  Eigen::Matrix4d M = A.matrix();
  M(3, 3) = 2.0;
  EXPECT_THROW(Sim3d{M}, Error);
  EXPECT_THROW(Sim3d(0.0, Eigen::Quaterniond::Identity(), t), Error);
  // A Sim3 with scale 1 acts like the SE3 with the same rotation and translation.
  const Sim3d S(1.0, sR.unit_quaternion(), t);
  const SE3d E(sR.so3(), t);
  const Eigen::Vector3d p(0.3, 0.2, -5.0);
  EXPECT_LT((S * p - E * p).norm(), 1e-14);
}

TEST(Sim3, FloatRoundTrip) {
  Rng rng(304);
  for (int i = 0; i < 500; ++i) {
    const Sim3f T = Sim3d::sampleUniform(rng).cast<float>();
    EXPECT_TRUE(Sim3f::exp(T.log()).isApprox(T, 1e-5f));
    const Eigen::Vector3f p = lie_test::randomVector(rng, 5.0).cast<float>();
    const auto act = [&p](const Sim3f& X) { return Eigen::Vector3f(X * p); };
    EXPECT_JACOBIAN_NEAR(T.dActionDLeft(p), test::numericJacobian(act, T, test::leftPlus<Sim3f>, 7, 1e-2), 5e-3);
  }
}

}  // namespace
}  // namespace rsvio
