// Tests of the shared numeric-Jacobian helper itself (tests/support/numeric_jacobian.h): a known
// analytic Jacobian passes, a deliberately wrong one fails with a useful message.
#include <gtest/gtest-spi.h>
#include <gtest/gtest.h>

#include <cmath>

#include "rsvio/lie/lie.h"
#include "support/numeric_jacobian.h"

namespace rsvio {
namespace {

using test::jacobianNear;
using test::numericJacobian;
using test::vectorPlus;

// f(x) = (x0 * x1, sin(x2), exp(x0)), J = [[x1, x0, 0], [0, 0, cos x2], [exp x0, 0, 0]].
Eigen::Vector3d f(const Eigen::Vector3d& x) { return Eigen::Vector3d(x[0] * x[1], std::sin(x[2]), std::exp(x[0])); }
Eigen::Matrix3d dfDx(const Eigen::Vector3d& x) {
  Eigen::Matrix3d J;
  J << x[1], x[0], 0, 0, 0, std::cos(x[2]), std::exp(x[0]), 0, 0;
  return J;
}

TEST(NumericJacobian, MatchesKnownAnalyticJacobian) {
  const Eigen::Vector3d x(0.3, -1.2, 2.0);
  const Eigen::MatrixXd num = numericJacobian(f, x, vectorPlus, 3);
  EXPECT_EQ(num.rows(), 3);
  EXPECT_EQ(num.cols(), 3);
  EXPECT_LT((num - dfDx(x)).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_TRUE(jacobianNear(dfDx(x), num, 1e-8, 1e-8));
  EXPECT_JACOBIAN_NEAR(dfDx(x), num, 1e-8);
}

TEST(NumericJacobian, WrongJacobianFails) {
  const Eigen::Vector3d x(0.3, -1.2, 2.0);
  const Eigen::MatrixXd num = numericJacobian(f, x, vectorPlus, 3);
  Eigen::Matrix3d wrong = dfDx(x);
  wrong(1, 2) = -wrong(1, 2);  // sign error
  const ::testing::AssertionResult r = jacobianNear(wrong, num, 1e-6, 1e-6);
  EXPECT_FALSE(r);
  const std::string msg = r.message();
  EXPECT_NE(msg.find("worst entry (1, 2)"), std::string::npos) << msg;
  EXPECT_NE(msg.find("Frobenius norm"), std::string::npos) << msg;
  EXPECT_NONFATAL_FAILURE(EXPECT_JACOBIAN_NEAR(wrong, num, 1e-6), "analytic - numeric");
  // A small relative error passes a loose tolerance and fails a tight one.
  const Eigen::Matrix3d close = dfDx(x) * (1 + 1e-5);
  EXPECT_TRUE(jacobianNear(close, num, 1e-4, 0.0));
  EXPECT_FALSE(jacobianNear(close, num, 1e-7, 0.0));
}

TEST(NumericJacobian, SizeMismatchAndNanFail) {
  EXPECT_FALSE(jacobianNear(Eigen::MatrixXd::Zero(2, 3), Eigen::MatrixXd::Zero(3, 2), 1.0, 1.0));
  Eigen::MatrixXd nan = Eigen::MatrixXd::Zero(2, 2);
  nan(0, 1) = std::nan("");
  EXPECT_FALSE(jacobianNear(nan, Eigen::MatrixXd::Zero(2, 2), 1.0, 1.0));
  EXPECT_FALSE(jacobianNear(Eigen::MatrixXd::Zero(2, 2), nan, 1.0, 1.0));
}

TEST(NumericJacobian, ScalarInputAndOutput) {
  const auto g = [](double t) { return std::sin(t) * t; };
  const Eigen::MatrixXd num = numericJacobian(g, 0.7, vectorPlus, 1);
  ASSERT_EQ(num.rows(), 1);
  EXPECT_NEAR(num(0, 0), std::cos(0.7) * 0.7 + std::sin(0.7), 1e-9);
}

TEST(NumericJacobian, MatrixOutputIsFlattenedColumnMajor) {
  const auto g = [](const Eigen::Vector2d& x) {
    Eigen::Matrix2d M;
    M << x[0], 2 * x[1], 3 * x[0], 4 * x[1];
    return M;
  };
  Eigen::Matrix<double, 4, 2> expected;
  expected << 1, 0, 3, 0, 0, 2, 0, 4;
  EXPECT_JACOBIAN_NEAR(expected, numericJacobian(g, Eigen::Vector2d(1, 2), vectorPlus, 2), 1e-9);
}

TEST(NumericJacobian, GroupCharts) {
  // Identity map on SO3 with left chart in and out is the identity; with left in and right out it is
  // R^T (exp(d) R = R exp(R^T d)), which checks that the charts are the ones documented.
  const SO3d R = SO3d::exp(Eigen::Vector3d(0.4, -0.1, 0.9));
  const auto id = [](const SO3d& X) { return X; };
  EXPECT_JACOBIAN_NEAR(Eigen::Matrix3d::Identity(),
                       numericJacobian(id, R, test::leftPlus<SO3d>, test::leftMinus<SO3d>, 3), 1e-9);
  EXPECT_JACOBIAN_NEAR(Eigen::Matrix3d::Identity(),
                       numericJacobian(id, R, test::rightPlus<SO3d>, test::rightMinus<SO3d>, 3), 1e-9);
  EXPECT_JACOBIAN_NEAR(R.matrix().transpose(),
                       numericJacobian(id, R, test::leftPlus<SO3d>, test::rightMinus<SO3d>, 3), 1e-9);
  EXPECT_JACOBIAN_NEAR(R.matrix(), numericJacobian(id, R, test::rightPlus<SO3d>, test::leftMinus<SO3d>, 3), 1e-9);
}

}  // namespace
}  // namespace rsvio
