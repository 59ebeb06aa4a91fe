// The typed pinhole model (plugins/camera/pinhole/pinhole_model.h) called directly, in double and
// float: reference values from OpenCV, round trips, Jacobians against numeric differences, domain.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <random>

#include "plugins/camera/pinhole/pinhole_model.h"
#include "support/numeric_jacobian.h"

namespace rsvio::pinhole {
namespace {

using test::numericJacobian;
using test::vectorPlus;

// 320x256 calibrations in the style of EuRoC (radtan) and TUM-VI (equidistant).
template <class S>
PinholeModel<S> radtanModel() {
  return PinholeModel<S>(Eigen::Matrix<S, 4, 1>(250, 245, 159.5, 127.5),
                         Eigen::Matrix<S, 4, 1>(-0.28, 0.07, 2e-4, -1.5e-4), S(1e-3));
}
template <class S>
PinholeModel<S> equidistantModel() {
  return PinholeModel<S>(Eigen::Matrix<S, 4, 1>(160, 161, 159.5, 127.5),
                         Eigen::Matrix<S, 4, 1>(0.0035, 0.0067, -0.0087, 0.0029), S(1e-3));
}
template <class S>
PinholeModel<S> plainModel() {
  return PinholeModel<S>(Eigen::Matrix<S, 4, 1>(250, 245, 159.5, 127.5), Eigen::Matrix<S, 4, 1>::Zero(), S(1e-3));
}

const Eigen::Vector3d kRefPoints[4] = {{0.3, -0.2, 1.0}, {-0.5, 0.4, 1.5}, {0.05, 0.02, 2.0}, {-1.2, -0.9, 1.1}};

// Values printed by OpenCV 4.6 cv::projectPoints (radtan, 4 coefficients) and cv::fisheye::projectPoints
// for the calibrations above: an implementation-independent reference.
TEST(PinholeModel, RadTanMatchesOpenCv) {
  const Eigen::Vector2d ref[4] = {{231.841100000000, 80.240333000000},
                                  {80.200767489712, 189.674169843621},
                                  {165.748682417461, 129.949529690145},
                                  {-37.310204919560, -17.013132330752}};
  const auto m = radtanModel<double>();
  for (int i = 0; i < 4; ++i) {
    Eigen::Vector2d uv;
    EXPECT_TRUE(m.project<Distortion::kRadTan>(kRefPoints[i], uv, nullptr));
    EXPECT_LT((uv - ref[i]).norm(), 1e-9) << i << ": " << uv.transpose();
  }
}

TEST(PinholeModel, EquidistantMatchesOpenCvFisheye) {
  const Eigen::Vector2d ref[4] = {{205.591625671043, 96.580201112342},
                                  {109.056519569945, 168.107001746194},
                                  {163.499043910318, 129.109615173903},
                                  {38.940204378015, 36.515029241534}};
  const auto m = equidistantModel<double>();
  for (int i = 0; i < 4; ++i) {
    Eigen::Vector2d uv;
    EXPECT_TRUE(m.project<Distortion::kEquidistant>(kRefPoints[i], uv, nullptr));
    EXPECT_LT((uv - ref[i]).norm(), 1e-9) << i << ": " << uv.transpose();
  }
}

template <Distortion D, class S>
void checkRoundTrip(const PinholeModel<S>& m, double tol_px) {
  using V2 = Eigen::Matrix<S, 2, 1>;
  using V3 = Eigen::Matrix<S, 3, 1>;
  int n = 0;
  for (int v = 0; v <= 255; v += 15) {
    for (int u = 0; u <= 319; u += 17) {
      const V2 uv{S(u), S(v)};
      V3 b;
      ASSERT_TRUE(m.template unproject<D>(uv, b, nullptr)) << u << "," << v;
      EXPECT_NEAR(double(b.norm()), 1.0, 10 * tol_px);
      V2 back;
      ASSERT_TRUE(m.template project<D>(V3(b * S(3.7)), back, nullptr));
      EXPECT_LT(double((back - uv).norm()), tol_px) << u << "," << v << " distortion " << int(D);
      ++n;
    }
  }
  EXPECT_GT(n, 300);
}

TEST(PinholeModel, RoundTripOverImageDouble) {
  checkRoundTrip<Distortion::kNone>(plainModel<double>(), 1e-9);
  checkRoundTrip<Distortion::kRadTan>(radtanModel<double>(), 1e-9);
  checkRoundTrip<Distortion::kEquidistant>(equidistantModel<double>(), 1e-9);
}

TEST(PinholeModel, RoundTripOverImageFloat) {
  checkRoundTrip<Distortion::kNone>(plainModel<float>(), 2e-3);
  checkRoundTrip<Distortion::kRadTan>(radtanModel<float>(), 2e-3);
  checkRoundTrip<Distortion::kEquidistant>(equidistantModel<float>(), 2e-3);
}

template <Distortion D>
void checkJacobians(const PinholeModel<double>& m, const PinholeModel<float>& mf) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> xy(-0.6, 0.6), z(0.5, 4.0);
  std::vector<Eigen::Vector3d> pts = {{0, 0, 1}, {1e-9, -1e-9, 1}, {0.6, 0.5, 1.0}};
  for (int i = 0; i < 20; ++i) {
    const double zz = z(rng);
    pts.emplace_back(xy(rng) * zz, xy(rng) * zz, zz);
  }
  for (const auto& p : pts) {
    Eigen::Vector2d uv;
    Eigen::Matrix<double, 2, 3> J;
    ASSERT_TRUE(m.project<D>(p, uv, &J));
    const auto f = [&](const Eigen::Vector3d& q) {
      Eigen::Vector2d r;
      m.project<D>(q, r, nullptr);
      return r;
    };
    EXPECT_JACOBIAN_NEAR(J, numericJacobian(f, p, vectorPlus, 3), 1e-6) << p.transpose();
    // Float: the same Jacobian to float precision.
    Eigen::Vector2f uvf;
    Eigen::Matrix<float, 2, 3> Jf;
    ASSERT_TRUE(mf.project<D>(p.cast<float>(), uvf, &Jf));
    EXPECT_JACOBIAN_NEAR(Jf, J, 1e-4);

    Eigen::Vector3d b;
    Eigen::Matrix<double, 3, 2> Jb;
    ASSERT_TRUE(m.unproject<D>(uv, b, &Jb));
    const auto g = [&](const Eigen::Vector2d& q) {
      Eigen::Vector3d r;
      m.unproject<D>(q, r, nullptr);
      return r;
    };
    EXPECT_JACOBIAN_NEAR(Jb, numericJacobian(g, uv, vectorPlus, 2, 1e-4), 1e-6) << uv.transpose();
  }
}

TEST(PinholeModel, JacobiansMatchNumeric) {
  checkJacobians<Distortion::kNone>(plainModel<double>(), plainModel<float>());
  checkJacobians<Distortion::kRadTan>(radtanModel<double>(), radtanModel<float>());
  checkJacobians<Distortion::kEquidistant>(equidistantModel<double>(), equidistantModel<float>());
}

template <Distortion D>
void checkBehind(const PinholeModel<double>& m) {
  Eigen::Vector2d uv;
  Eigen::Matrix<double, 2, 3> J;
  EXPECT_FALSE(m.project<D>(Eigen::Vector3d(0.1, 0.2, -1.0), uv, &J));
  EXPECT_FALSE(m.project<D>(Eigen::Vector3d(0.1, 0.2, 0.0), uv, &J));
  EXPECT_FALSE(m.project<D>(Eigen::Vector3d(0.0, 0.0, 0.5e-3), uv, &J));  // below min_depth 1e-3
  EXPECT_FALSE(m.project<D>(Eigen::Vector3d(0.0, 0.0, std::nan("")), uv, &J));
  EXPECT_TRUE(m.project<D>(Eigen::Vector3d(0.0, 0.0, 2e-3), uv, &J));
}

TEST(PinholeModel, PointsBehindOrTooCloseAreInvalid) {
  checkBehind<Distortion::kNone>(plainModel<double>());
  checkBehind<Distortion::kRadTan>(radtanModel<double>());
  checkBehind<Distortion::kEquidistant>(equidistantModel<double>());
}

TEST(PinholeModel, RadTanFoldOverIsInvalid) {
  // 1 + 3 k1 r^2 = 0 at r^2 = 1/0.84 with k1 = -0.28, k2 = 0: beyond it the polynomial folds back.
  const PinholeModel<double> m(Eigen::Vector4d(250, 250, 160, 128), Eigen::Vector4d(-0.28, 0, 0, 0), 1e-3);
  Eigen::Vector2d uv;
  EXPECT_TRUE(m.project<Distortion::kRadTan>(Eigen::Vector3d(1.0, 0.0, 1.0), uv, nullptr));
  EXPECT_FALSE(m.project<Distortion::kRadTan>(Eigen::Vector3d(1.2, 0.0, 1.0), uv, nullptr));
  EXPECT_FALSE(m.project<Distortion::kRadTan>(Eigen::Vector3d(3.0, 0.0, 1.0), uv, nullptr));
  // A distorted radius beyond the model's maximum has no pre-image.
  Eigen::Vector3d b;
  EXPECT_FALSE(m.unproject<Distortion::kRadTan>(Eigen::Vector2d(160 + 250 * 0.9, 128), b, nullptr));
}

TEST(PinholeModel, EquidistantBeyondNinetyDegreesIsInvalid) {
  const auto m = equidistantModel<double>();
  // theta_d well past pi/2 cannot come from a point in front of the camera.
  Eigen::Vector3d b;
  EXPECT_FALSE(m.unproject<Distortion::kEquidistant>(Eigen::Vector2d(159.5 + 160 * 2.0, 127.5), b, nullptr));
  EXPECT_TRUE(m.unproject<Distortion::kEquidistant>(Eigen::Vector2d(159.5 + 160 * 1.2, 127.5), b, nullptr));
  EXPECT_GT(b.z(), 0.0);
}

TEST(PinholeModel, PrincipalPointUnprojectsToOpticalAxis) {
  const auto m = equidistantModel<double>();
  Eigen::Vector3d b;
  Eigen::Matrix<double, 3, 2> J;
  ASSERT_TRUE(m.unproject<Distortion::kEquidistant>(Eigen::Vector2d(159.5, 127.5), b, &J));
  EXPECT_LT((b - Eigen::Vector3d::UnitZ()).norm(), 1e-15);
  EXPECT_NEAR(J(0, 0), 1.0 / 160, 1e-12);
  EXPECT_NEAR(J(1, 1), 1.0 / 161, 1e-12);
}

}  // namespace
}  // namespace rsvio::pinhole
