// Umeyama alignment recovers a known Sim(3) / SE(3) exactly on noise-free synthetic trajectories.
#include "rsvio/eval/alignment.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <random>

#include "rsvio/core/error.h"

using namespace rsvio;
using namespace rsvio::eval;

namespace {

Eigen::Matrix3Xd randomPoints(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-5.0, 5.0);
  Eigen::Matrix3Xd p(3, n);
  for (int i = 0; i < n; ++i) p.col(i) = Eigen::Vector3d(u(rng), u(rng), 0.3 * u(rng));
  return p;
}

}  // namespace

TEST(Umeyama, RecoversKnownSim3) {
  const Eigen::Matrix3Xd est = randomPoints(200, 1);
  const double s = 2.37;
  const Eigen::Matrix3d R = Eigen::AngleAxisd(2.1, Eigen::Vector3d(0.3, -1.0, 0.5).normalized()).toRotationMatrix();
  const Eigen::Vector3d t(10.0, -3.0, 0.7);
  const Eigen::Matrix3Xd gt = ((s * R) * est).colwise() + t;
  const Alignment a = umeyamaAlignment(est, gt, AlignMode::kSim3);
  EXPECT_NEAR(a.scale, s, 1e-9);
  EXPECT_LT((a.R - R).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_LT((a.t - t).cwiseAbs().maxCoeff(), 1e-9);
  for (int i = 0; i < est.cols(); ++i) EXPECT_LT((a.apply(est.col(i)) - gt.col(i)).norm(), 1e-9);
}

TEST(Umeyama, RecoversKnownSE3AndKeepsScaleOne) {
  const Eigen::Matrix3Xd est = randomPoints(50, 2);
  const Eigen::Matrix3d R = Eigen::AngleAxisd(-0.8, Eigen::Vector3d(1, 1, 0).normalized()).toRotationMatrix();
  const Eigen::Vector3d t(-1.0, 2.0, 3.0);
  const Eigen::Matrix3Xd gt = (R * est).colwise() + t;
  const Alignment a = umeyamaAlignment(est, gt, AlignMode::kSE3);
  EXPECT_EQ(a.scale, 1.0);
  EXPECT_LT((a.R - R).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_LT((a.t - t).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_NEAR(a.R.determinant(), 1.0, 1e-12);
}

TEST(Umeyama, RotationNearPiAndPlanarPointsStayProperRotations) {
  // A planar point set makes one singular value zero: the reflection check must still give det +1.
  Eigen::Matrix3Xd est = randomPoints(30, 3);
  est.row(2).setZero();
  const Eigen::Matrix3d R = Eigen::AngleAxisd(M_PI - 1e-7, Eigen::Vector3d(0.2, 0.9, -0.1).normalized()).toRotationMatrix();
  const Eigen::Matrix3Xd gt = (0.5 * R * est).colwise() + Eigen::Vector3d(1, 2, 3);
  const Alignment a = umeyamaAlignment(est, gt, AlignMode::kSim3);
  EXPECT_NEAR(a.R.determinant(), 1.0, 1e-12);
  EXPECT_LT((a.R - R).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_NEAR(a.scale, 0.5, 1e-9);
}

TEST(Umeyama, AgreesWithEigenOnNoisyData) {
  Eigen::Matrix3Xd est = randomPoints(100, 4);
  std::mt19937 rng(5);
  std::normal_distribution<double> n(0.0, 0.05);
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitY()).toRotationMatrix();
  Eigen::Matrix3Xd gt = (1.3 * R * est).colwise() + Eigen::Vector3d(0.1, 0.2, 0.3);
  for (int i = 0; i < gt.cols(); ++i) gt.col(i) += Eigen::Vector3d(n(rng), n(rng), n(rng));
  for (bool with_scale : {false, true}) {
    const Eigen::Matrix4d e = Eigen::umeyama(est, gt, with_scale);
    const Alignment a = umeyamaAlignment(est, gt, with_scale ? AlignMode::kSim3 : AlignMode::kSE3);
    EXPECT_LT((a.scale * a.R - e.topLeftCorner<3, 3>()).cwiseAbs().maxCoeff(), 1e-9);
    EXPECT_LT((a.t - e.topRightCorner<3, 1>()).cwiseAbs().maxCoeff(), 1e-9);
  }
}

TEST(Umeyama, NoneIsIdentityAndDegenerateCasesThrow) {
  const Eigen::Matrix3Xd p = randomPoints(2, 6);
  const Alignment none = umeyamaAlignment(p, p * 3.0, AlignMode::kNone);
  EXPECT_EQ(none.scale, 1.0);
  EXPECT_TRUE(none.R.isIdentity());
  EXPECT_TRUE(none.t.isZero());
  EXPECT_THROW(umeyamaAlignment(p, p, AlignMode::kSE3), Error);  // 2 pairs
  const Eigen::Matrix3Xd same = Eigen::Matrix3Xd::Ones(3, 5);
  EXPECT_THROW(umeyamaAlignment(same, randomPoints(5, 7), AlignMode::kSim3), Error);
}

TEST(AlignMode, ParsesNamesAndRejectsOthers) {
  EXPECT_EQ(parseAlignMode("SE3"), AlignMode::kSE3);
  EXPECT_EQ(parseAlignMode("sim3"), AlignMode::kSim3);
  EXPECT_EQ(parseAlignMode("none"), AlignMode::kNone);
  try {
    parseAlignMode("affine");
    FAIL() << "no throw";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("--align = 'affine'"), std::string::npos) << e.what();
  }
}
