// SO3: group axioms, exp/log on the principal range and at its edges (0, pi - 1e-9, pi), the adjoint
// property (paper eq. 26), and every Jacobian against numeric differences.
#include <gtest/gtest.h>

#include "framework/lie/lie_test_util.h"
#include "rsvio/lie/lie.h"
#include "support/numeric_jacobian.h"

namespace rsvio {
namespace {

using lie_test::kPi;
using test::leftMinus;
using test::leftPlus;
using test::numericJacobian;
using test::rightMinus;
using test::rightPlus;
using test::vectorPlus;

TEST(SO3, ExpLogRoundTripRandom) {
  lie_test::Rng rng(1);
  for (int i = 0; i < lie_test::kSamples; ++i) {
    const Eigen::Vector3d w = lie_test::randomRotationVector(rng);
    ASSERT_LT((SO3d::exp(w).log() - w).norm(), 1e-12) << w.transpose();
    const SO3d R = SO3d::sampleUniform(rng);
    ASSERT_TRUE(SO3d::exp(R.log()).isApprox(R, 1e-13));
    ASSERT_LE(R.log().norm(), kPi + 1e-15);
  }
}

TEST(SO3, ExpMatchesRodrigues) {
  lie_test::Rng rng(2);
  for (int i = 0; i < lie_test::kSamples; ++i) {
    const Eigen::Vector3d w = lie_test::randomRotationVector(rng, 3.0 * kPi);
    const Eigen::Matrix3d R_ref = Eigen::AngleAxisd(w.norm(), w.normalized()).toRotationMatrix();
    ASSERT_LT((SO3d::exp(w).matrix() - R_ref).cwiseAbs().maxCoeff(), 1e-14);
  }
}

TEST(SO3, EdgeAngles) {
  for (const Eigen::Vector3d& w : lie_test::edgeRotationVectors()) {
    const double t = w.norm();
    const SO3d R = SO3d::exp(w);
    const Eigen::Matrix3d R_ref = t > 0 ? Eigen::AngleAxisd(t, w / t).toRotationMatrix() : Eigen::Matrix3d::Identity();
    EXPECT_LT((R.matrix() - R_ref).cwiseAbs().maxCoeff(), 1e-15) << "angle " << t;
    // From the matrix too: the quaternion-from-matrix path near pi is where naive logs fail.
    const SO3d R_m(R_ref);
    for (const SO3d& X : {R, R_m}) {
      const Eigen::Vector3d l = X.log();
      EXPECT_TRUE(l.allFinite());
      EXPECT_TRUE(SO3d::exp(l).isApprox(X, 1e-14)) << "angle " << t;
      if (t < kPi) {
        EXPECT_LT((l - w).norm(), 1e-14) << "angle " << t;
      } else {  // exactly pi: the axis sign is arbitrary
        EXPECT_NEAR(l.norm(), kPi, 1e-15);
        EXPECT_LT(std::min((l - w).norm(), (l + w).norm()), 1e-14);
      }
    }
  }
}

TEST(SO3, LogOfQuaternionWithNegativeRealPart) {
  // q and -q are the same rotation; log must return the angle <= pi either way.
  const Eigen::Vector3d w(0.3, -0.2, 0.1);
  const Eigen::Quaterniond q = SO3d::exp(w).unit_quaternion();
  SO3d R;
  R.setQuaternion(Eigen::Quaterniond(-q.coeffs()));
  EXPECT_LT((R.log() - w).norm(), 1e-15);
}

TEST(SO3, HatVee) {
  lie_test::Rng rng(3);
  for (int i = 0; i < lie_test::kSamples; ++i) {
    const Eigen::Vector3d w = lie_test::randomVector(rng, 10.0), v = lie_test::randomVector(rng, 10.0);
    ASSERT_EQ(SO3d::vee(SO3d::hat(w)), w);
    ASSERT_LT((SO3d::hat(w) * v - w.cross(v)).norm(), 1e-13);
    ASSERT_EQ(SO3d::hat(w).transpose(), -SO3d::hat(w));
  }
}

TEST(SO3, GroupAxiomsAndAction) {
  lie_test::Rng rng(4);
  for (int i = 0; i < lie_test::kSamples; ++i) {
    const SO3d A = SO3d::sampleUniform(rng), B = SO3d::sampleUniform(rng), C = SO3d::sampleUniform(rng);
    const Eigen::Vector3d p = lie_test::randomVector(rng, 5.0);
    ASSERT_TRUE((A.inverse() * A).isApprox(SO3d::Identity(), 1e-15));
    ASSERT_TRUE((A * A.inverse()).isApprox(SO3d(), 1e-15));
    ASSERT_TRUE(((A * B) * C).isApprox(A * (B * C), 1e-14));
    ASSERT_LT(((A * B).matrix() - A.matrix() * B.matrix()).norm(), 1e-14);
    ASSERT_LT((A * p - A.matrix() * p).norm(), 1e-14);
    ASSERT_LT((A.inverse().matrix() - A.matrix().transpose()).norm(), 1e-15);
    ASSERT_LT((A.matrix().transpose() * A.matrix() - Eigen::Matrix3d::Identity()).norm(), 4e-15);
  }
}

TEST(SO3, CompositionStaysUnit) {
  lie_test::Rng rng(5);
  SO3d R;
  for (int i = 0; i < 100000; ++i) R *= SO3d::exp(lie_test::randomRotationVector(rng, 0.1));
  EXPECT_NEAR(R.unit_quaternion().squaredNorm(), 1.0, 1e-10);
}

TEST(SO3, AdjointProperty) {  // paper eq. 26: R exp(d) = exp(Adj(R) d) R
  lie_test::Rng rng(6);
  for (int i = 0; i < lie_test::kSamples; ++i) {
    const SO3d R = SO3d::sampleUniform(rng);
    const Eigen::Vector3d d = lie_test::randomRotationVector(rng);
    ASSERT_TRUE((R * SO3d::exp(d)).isApprox(SO3d::exp(R.Adj() * d) * R, 1e-13));
    ASSERT_LT((SO3d::hat(R.Adj() * d) - R.matrix() * SO3d::hat(d) * R.matrix().transpose()).norm(), 1e-13);
  }
}

TEST(SO3, ConstructorsCheckTheirInput) {
  EXPECT_THROW(SO3d(Eigen::Quaterniond(1.0, 0.1, 0.0, 0.0)), Error);
  EXPECT_NO_THROW(SO3d(Eigen::Quaterniond(1.0 + 1e-8, 0.0, 0.0, 0.0)));
  EXPECT_EQ(SO3d(Eigen::Quaterniond(1.0 + 1e-8, 0.0, 0.0, 0.0)).unit_quaternion().w(), 1.0);
  SO3d R;
  EXPECT_THROW(R.setQuaternion(Eigen::Quaterniond(0.0, 0.0, 0.0, 1e-12)), Error);
  R.setQuaternion(Eigen::Quaterniond(2.0, 0.0, 0.0, 2.0));
  EXPECT_LT((R.log() - Eigen::Vector3d(0, 0, kPi / 2)).norm(), 1e-15);

  EXPECT_THROW(SO3d(Eigen::Matrix3d(Eigen::Matrix3d::Identity() * 1.01)), Error);
  EXPECT_THROW(SO3d(Eigen::Matrix3d(Eigen::Vector3d(1, 1, -1).asDiagonal())), Error);  // reflection
  const Eigen::Matrix3d M = SO3d::rotZ(0.3).matrix() + 1e-3 * Eigen::Matrix3d::Ones();
  EXPECT_THROW(SO3d{M}, Error);
  EXPECT_TRUE(SO3d::fitToSO3(M).isApprox(SO3d::rotZ(0.3), 2e-3));
  EXPECT_TRUE(SO3d::fitToSO3(SO3d::rotX(1.0).matrix()).isApprox(SO3d::rotX(1.0), 1e-15));
}

TEST(SO3, ParamsAndCast) {
  const SO3d R = SO3d::exp(Eigen::Vector3d(0.1, 0.2, 0.3));
  EXPECT_EQ(R.params(), R.unit_quaternion().coeffs());
  EXPECT_EQ(R.data()[3], R.unit_quaternion().w());
  const SO3f Rf = R.cast<float>();
  EXPECT_LT((Rf.log().cast<double>() - R.log()).norm(), 1e-6);
  EXPECT_TRUE(Rf.cast<double>().isApprox(R, 1e-6));
}

// Series and closed form of every coefficient must agree where the branch switches.
TEST(SO3, CoefficientsContinuousAtBranchSwitch) {
  for (double t0 : {lie::Constants<double>::seriesAngle(), lie::Constants<double>::invSeriesAngle(),
                    lie::Constants<double>::epsilon()}) {
    // lo takes the series branch, hi = t0 the closed form.
    const double lo = std::nextafter(t0, 0.0), hi = t0;
    EXPECT_NEAR(lie::sinOverTheta(lo), lie::sinOverTheta(hi), 1e-15);
    EXPECT_NEAR(lie::oneMinusCosOverTheta2(lo), lie::oneMinusCosOverTheta2(hi), 1e-15);
    EXPECT_NEAR(lie::thetaMinusSinOverTheta3(lo), lie::thetaMinusSinOverTheta3(hi), 1e-15);
    EXPECT_NEAR(lie::se3QCoeff2(lo), lie::se3QCoeff2(hi), 1e-15);
    EXPECT_NEAR(lie::se3QCoeff3(lo), lie::se3QCoeff3(hi), 2e-15);
    EXPECT_NEAR(lie::invLeftJacobianCoeff(lo), lie::invLeftJacobianCoeff(hi), 1e-15);
  }
  // Limits at zero and the value at pi.
  EXPECT_EQ(lie::oneMinusCosOverTheta2(0.0), 0.5);
  EXPECT_EQ(lie::thetaMinusSinOverTheta3(0.0), 1.0 / 6.0);
  EXPECT_EQ(lie::se3QCoeff2(0.0), 1.0 / 24.0);
  EXPECT_EQ(lie::se3QCoeff3(0.0), 1.0 / 120.0);
  EXPECT_EQ(lie::invLeftJacobianCoeff(0.0), 1.0 / 12.0);
  EXPECT_NEAR(lie::invLeftJacobianCoeff(kPi), 1.0 / (kPi * kPi), 1e-16);
  EXPECT_NEAR(lie::invLeftJacobianCoeff(1.3), 1.0 / 1.69 - (1 + std::cos(1.3)) / (2 * 1.3 * std::sin(1.3)), 1e-15);
}

// Rotation vectors for the Jacobian checks: random plus edge angles.
std::vector<Eigen::Vector3d> jacobianSamples(uint64_t seed, double max_angle) {
  lie_test::Rng rng(seed);
  std::vector<Eigen::Vector3d> out;
  for (int i = 0; i < lie_test::kJacobianSamples; ++i) out.push_back(lie_test::randomRotationVector(rng, max_angle));
  for (const auto& w : lie_test::edgeRotationVectors())
    if (w.norm() <= max_angle) out.push_back(w);
  return out;
}

TEST(SO3, LeftAndRightJacobians) {
  // exp(phi + d) = exp(Jl d) exp(phi) = exp(phi) exp(Jr d); no log cut is crossed, so all angles up to pi.
  for (const Eigen::Vector3d& phi : jacobianSamples(10, kPi)) {
    const auto f = [](const Eigen::Vector3d& x) { return SO3d::exp(x); };
    EXPECT_JACOBIAN_NEAR(SO3d::leftJacobian(phi), numericJacobian(f, phi, vectorPlus, leftMinus<SO3d>, 3), 1e-8);
    EXPECT_JACOBIAN_NEAR(SO3d::rightJacobian(phi), numericJacobian(f, phi, vectorPlus, rightMinus<SO3d>, 3), 1e-8);
    EXPECT_LT((SO3d::leftJacobian(phi) * SO3d::leftJacobianInverse(phi) - Eigen::Matrix3d::Identity()).norm(), 1e-13);
    EXPECT_LT((SO3d::rightJacobian(phi) * SO3d::rightJacobianInverse(phi) - Eigen::Matrix3d::Identity()).norm(),
              1e-13);
    EXPECT_LT((SO3d::rightJacobian(phi) - SO3d::leftJacobian(phi).transpose()).norm(), 1e-15);
  }
}

TEST(SO3, InverseJacobiansAreDerivativesOfLog) {
  // log(exp(d) R) = log R + Jl^-1 d, log(R exp(d)) = log R + Jr^-1 d. Stay away from the cut at pi.
  for (const Eigen::Vector3d& phi : jacobianSamples(11, kPi - 1e-3)) {
    const SO3d R = SO3d::exp(phi);
    const auto log = [](const SO3d& X) { return X.log(); };
    EXPECT_JACOBIAN_NEAR(SO3d::leftJacobianInverse(phi), numericJacobian(log, R, leftPlus<SO3d>, 3), 1e-7);
    EXPECT_JACOBIAN_NEAR(SO3d::rightJacobianInverse(phi), numericJacobian(log, R, rightPlus<SO3d>, 3), 1e-7);
  }
}

TEST(SO3, ActionJacobians) {
  lie_test::Rng rng(12);
  for (int i = 0; i < lie_test::kJacobianSamples; ++i) {
    const SO3d R = SO3d::sampleUniform(rng);
    const Eigen::Vector3d p = lie_test::randomVector(rng, 10.0);
    const auto act = [&p](const SO3d& X) { return Eigen::Vector3d(X * p); };
    EXPECT_JACOBIAN_NEAR(R.dActionDLeft(p), numericJacobian(act, R, leftPlus<SO3d>, 3), 1e-8);
    EXPECT_JACOBIAN_NEAR(R.dActionDRight(p), numericJacobian(act, R, rightPlus<SO3d>, 3), 1e-8);
    // d(R p)/dp = R
    const auto act_p = [&R](const Eigen::Vector3d& x) { return Eigen::Vector3d(R * x); };
    EXPECT_JACOBIAN_NEAR(R.matrix(), numericJacobian(act_p, p, vectorPlus, 3), 1e-8);
  }
}

TEST(SO3, FloatExpLogAndJacobians) {
  lie_test::Rng rng(13);
  for (int i = 0; i < lie_test::kJacobianSamples; ++i) {
    const Eigen::Vector3f w = lie_test::randomRotationVector(rng, 3.0).cast<float>();
    ASSERT_LT((SO3f::exp(w).log() - w).norm(), 2e-6f);
    const auto f = [](const Eigen::Vector3f& x) { return SO3f::exp(x); };
    EXPECT_JACOBIAN_NEAR(SO3f::leftJacobian(w), numericJacobian(f, w, vectorPlus, leftMinus<SO3f>, 3, 1e-2), 2e-3);
    EXPECT_JACOBIAN_NEAR(SO3f::rightJacobian(w), numericJacobian(f, w, vectorPlus, rightMinus<SO3f>, 3, 1e-2), 2e-3);
    const auto log = [](const SO3f& X) { return X.log(); };
    EXPECT_JACOBIAN_NEAR(SO3f::leftJacobianInverse(w), numericJacobian(log, SO3f::exp(w), leftPlus<SO3f>, 3, 1e-2),
                         2e-3);
  }
  for (const Eigen::Vector3d& w : lie_test::edgeRotationVectors()) {
    const SO3f R = SO3f::exp(w.cast<float>());
    EXPECT_TRUE(SO3f::exp(R.log()).isApprox(R, 1e-6f));
    EXPECT_TRUE(SO3f::leftJacobianInverse(w.cast<float>()).allFinite());
  }
}

}  // namespace
}  // namespace rsvio
