// solver.dense through the plugin host: messages of refused systems, both methods, param validation.
#include <gtest/gtest.h>

#include "support/plugin_contracts.h"

namespace rsvio::test {
namespace {

TEST(DenseSolver, MessagesSayWhy) {
  auto s = makePlugin<SolverBackend>("solver.dense");
  Eigen::VectorXd x;
  SolverStats stats;
  Eigen::Matrix3d H = Eigen::Matrix3d::Identity();
  H(1, 1) = -2.0;
  EXPECT_FALSE(s->solveDense(H, Eigen::Vector3d::Ones(), x, &stats));
  EXPECT_NE(stats.message.find("solver.dense: H is not positive definite"), std::string::npos) << stats.message;
  EXPECT_FALSE(s->solveDense(Eigen::Matrix3d::Identity(), Eigen::Vector2d::Ones(), x, &stats));
  EXPECT_EQ(stats.message, "solver.dense: size mismatch: H is 3x3, b has 2 rows");
  H = Eigen::Matrix3d::Identity();
  H(0, 2) = H(2, 0) = std::nan("");
  EXPECT_FALSE(s->solveDense(H, Eigen::Vector3d::Ones(), x, &stats));
  EXPECT_EQ(stats.message, "solver.dense: H or b holds NaN or inf");
  EXPECT_TRUE(s->solveDense(Eigen::MatrixXd(0, 0), Eigen::VectorXd(0), x, &stats));
  EXPECT_EQ(x.size(), 0);
}

TEST(DenseSolver, LltRefusesWhatLdltRefuses) {
  auto llt = makePlugin<SolverBackend>("solver.dense", {{"method", "llt"}});
  Eigen::Matrix2d H;
  H << 1.0, 2.0, 2.0, 1.0;  // eigenvalues 3 and -1
  Eigen::VectorXd x;
  SolverStats stats;
  EXPECT_FALSE(llt->solveDense(H, Eigen::Vector2d(1.0, 0.0), x, &stats));
  EXPECT_NE(stats.message.find("not positive definite"), std::string::npos) << stats.message;
}

TEST(DenseSolver, BothMethodsAgree) {
  auto ldlt = makePlugin<SolverBackend>("solver.dense", {{"method", "ldlt"}});
  auto llt = makePlugin<SolverBackend>("solver.dense", {{"method", "llt"}});
  const Eigen::MatrixXd H = randomSpd(12, 5);
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(12, -1.0, 2.0);
  Eigen::VectorXd x1, x2;
  ASSERT_TRUE(ldlt->solveDense(H, b, x1));
  ASSERT_TRUE(llt->solveDense(H, b, x2));
  EXPECT_LT((x1 - x2).norm(), 1e-12 * x1.norm());
}

TEST(DenseSolver, ParamsAreValidatedLikeAConfigSlot) {
  try {
    makePlugin<SolverBackend>("solver.dense", {{"method", "qr"}});
    FAIL() << "method qr accepted";
  } catch (const ConfigError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("solver.dense.params.method"), std::string::npos) << msg;
    EXPECT_NE(msg.find("ldlt"), std::string::npos) << msg;
  }
}

}  // namespace
}  // namespace rsvio::test
