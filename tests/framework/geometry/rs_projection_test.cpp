// Rolling-shutter projection (rsvio/geometry/rs_projection.h): the constraint, an independent
// brute-force row search, every Jacobian against numeric differences (left perturbation for poses),
// and the edge cases: zero line delay, image border, depth near zero, large and singular twists.
// The camera is camera.pinhole with radtan distortion, loaded through the plugin host.
#include <gtest/gtest.h>

#include <cmath>

#include "rsvio/geometry/rs_projection.h"
#include "support/numeric_jacobian.h"
#include "support/plugin_contracts.h"

namespace rsvio::test {
namespace {

class RsProjectionTest : public ::testing::Test {
 protected:
  void SetUp() override {
    CameraCalibration c = defaultContractCalibration();
    c.distortion = "radtan";
    c.intrinsics = Eigen::Vector4d(250.0, 245.0, 159.5, 127.5);
    c.distortion_coeffs = Eigen::Vector4d(-0.28, 0.07, 2e-4, -1.5e-4);
    cam_ = makePlugin<CameraModel>("camera.pinhole");
    cam_->setCalibration(c);
    timing_ = RowTiming::rolling(c.rowZero(), 3e-5, true);
    target_.T_c_w0 = SE3d(SO3d::exp(Vec3(0.1, -0.2, 0.05)), Vec3(0.3, -0.1, 0.2));
    target_.xi << 0.8, -0.3, 0.5, 0.6, -1.2, 0.4;
    host_.T_c_w0 = SE3d(SO3d::exp(Vec3(0.05, -0.1, 0.02)), Vec3(0.1, 0.0, 0.3));
    host_.xi << -0.5, 0.2, 0.3, -0.4, 0.9, -0.2;
  }

  // A world point seen by the target's central pose at pixel-ish direction (x, y) and depth z.
  Vec3 worldPoint(double x, double y, double z) const { return target_.T_c_w0.inverse() * Vec3(x * z, y * z, z); }

  RsProjectionOptions exact() const {
    RsProjectionOptions o;
    o.tolerance_px = 1e-11;
    o.max_iterations = 50;
    return o;
  }

  void checkWorldJacobians(const RowTiming& timing, const RsFrame& f, const Vec3& X, double tol = 1e-6) {
    const RsProjection r = projectRollingShutter(*cam_, timing, f, X, exact());
    ASSERT_TRUE(r.valid) << X.transpose();
    const auto uvAt = [&](const RowTiming& tm, const RsFrame& ff, const Vec3& XX) {
      RsProjectionOptions o = exact();
      o.jacobians = false;
      return projectRollingShutter(*cam_, tm, ff, XX, o).uv;
    };
    const auto byPose = [&](const SE3d& T) { return uvAt(timing, RsFrame{T, f.xi, f.w_dot}, X); };
    const auto byTwist = [&](const Vec6& xi) { return uvAt(timing, RsFrame{f.T_c_w0, xi, f.w_dot}, X); };
    const auto byPoint = [&](const Vec3& XX) { return uvAt(timing, f, XX); };
    const auto byDelay = [&](double ld) {
      RowTiming tm = timing;
      tm.line_delay_s = ld;
      return uvAt(tm, f, X);
    };
    EXPECT_JACOBIAN_NEAR_TOL(r.d_uv_d_T0, numericJacobian(byPose, f.T_c_w0, leftPlus<SE3d>, 6, 1e-5), tol, 1e-5);
    EXPECT_JACOBIAN_NEAR_TOL(r.d_uv_d_xi, numericJacobian(byTwist, f.xi, vectorPlus, 6, 1e-5), tol, 1e-5);
    EXPECT_JACOBIAN_NEAR_TOL(r.d_uv_d_X, numericJacobian(byPoint, X, vectorPlus, 3, 1e-5), tol, 1e-5);
    EXPECT_JACOBIAN_NEAR_TOL(r.d_uv_d_line_delay,
                             numericJacobian(byDelay, timing.line_delay_s, vectorPlus, 1, 1e-8), tol, 1e-2);
  }

  std::unique_ptr<CameraModel> cam_;
  RowTiming timing_;
  RsFrame target_, host_;
};

TEST_F(RsProjectionTest, GlobalShutterIsOnePlainProjection) {
  const RowTiming gs = RowTiming::global(timing_.y0);
  const Vec3 X = worldPoint(0.2, -0.3, 3.0);
  const RsProjection r = projectRollingShutter(*cam_, gs, target_, X);
  Vec2 uv;
  ASSERT_TRUE(cam_->project(Vec3(target_.T_c_w0 * X), uv));
  EXPECT_TRUE(r.valid);
  EXPECT_TRUE(r.converged);
  EXPECT_EQ(r.iterations, 1);
  EXPECT_EQ(r.t_s, 0.0);
  EXPECT_LT((r.uv - uv).norm(), 1e-12);
  EXPECT_EQ(r.d_uv_d_xi.norm(), 0.0);  // t = 0: the twist does not act
  EXPECT_EQ(r.d_uv_d_line_delay.norm(), 0.0);
}

TEST_F(RsProjectionTest, SolutionSatisfiesTheConstraint) {
  for (double y : {-0.45, -0.1, 0.0, 0.3, 0.45}) {
    for (double x : {-0.55, 0.0, 0.5}) {
      const Vec3 X = worldPoint(x, y, 2.5);
      const RsProjection r = projectRollingShutter(*cam_, timing_, target_, X);
      ASSERT_TRUE(r.valid);
      EXPECT_LE(r.iterations, 4) << "Newton converges in a few steps for ordinary motion";
      EXPECT_NEAR(r.t_s, timing_.rowTime(r.uv.y()), 1e-6 * timing_.line_delay_s);
      Vec2 uv;
      ASSERT_TRUE(cam_->project(Vec3(SE3d::exp(target_.xi * r.t_s) * (target_.T_c_w0 * X)), uv));
      EXPECT_LT((uv - r.uv).norm(), 1e-6);
    }
  }
}

// Independent check: sample the row time finely, find where the projected row equals the row whose
// time it is, refine by bisection, and compare with the Newton solution.
Vec2 bruteForceRs(const CameraModel& cam, const RowTiming& tm, const RsFrame& f, const Vec3& X, int* roots) {
  const auto rowAt = [&](double t, Vec2* uv) {
    Vec2 q;
    cam.project(Vec3(SE3d::exp(f.xi * t) * (f.T_c_w0 * X)), q);
    if (uv) *uv = q;
    return q.y() - (tm.y0 + t / tm.dtDv());
  };
  const double t_span = std::abs(tm.dtDv()) * (cam.height() + 100.0);
  const int n = 4000;
  Vec2 best = Vec2::Constant(NAN);
  *roots = 0;
  double t_prev = -t_span, g_prev = rowAt(t_prev, nullptr);
  for (int i = 1; i <= n; ++i) {
    const double t = -t_span + 2.0 * t_span * i / n;
    const double g = rowAt(t, nullptr);
    if ((g_prev < 0) != (g < 0)) {
      double lo = t_prev, hi = t, g_lo = g_prev;
      for (int k = 0; k < 100; ++k) {
        const double mid = 0.5 * (lo + hi);
        const double gm = rowAt(mid, nullptr);
        if ((gm < 0) == (g_lo < 0)) {
          lo = mid;
          g_lo = gm;
        } else {
          hi = mid;
        }
      }
      rowAt(0.5 * (lo + hi), &best);
      ++*roots;
    }
    t_prev = t;
    g_prev = g;
  }
  return best;
}

TEST_F(RsProjectionTest, MatchesBruteForceRowSearch) {
  RsFrame fast = target_;
  fast.xi << 2.0, -1.5, 1.0, 1.5, -2.5, 1.0;  // large motion: several pixels of rolling-shutter shift
  double max_shift = 0.0;
  for (const RsFrame* f : {&target_, &fast}) {
    for (bool top_down : {true, false}) {
      const RowTiming tm = RowTiming::rolling(timing_.y0, 5e-5, top_down);
      for (double y : {-0.45, -0.15, 0.2, 0.45}) {
        for (double x : {-0.5, 0.1, 0.55}) {
          const Vec3 X = worldPoint(x, y, 1.5);
          const RsProjection r = projectRollingShutter(*cam_, tm, *f, X);
          int roots = 0;
          const Vec2 uv = bruteForceRs(*cam_, tm, *f, X, &roots);
          ASSERT_EQ(roots, 1);
          ASSERT_TRUE(r.valid);
          EXPECT_LT((r.uv - uv).norm(), 0.01) << r.uv.transpose() << " vs " << uv.transpose();
          const Vec2 gs = projectRollingShutter(*cam_, RowTiming::global(tm.y0), *f, X).uv;
          if (f == &fast) max_shift = std::max(max_shift, (r.uv - gs).norm());
        }
      }
    }
  }
  EXPECT_GT(max_shift, 2.0) << "the fast case must exercise the rolling shutter";
}

TEST_F(RsProjectionTest, WorldPointJacobiansMatchNumeric) {
  for (bool top_down : {true, false}) {
    const RowTiming tm = RowTiming::rolling(timing_.y0, 3e-5, top_down);
    for (double y : {-0.4, 0.0, 0.35})
      for (double x : {-0.5, 0.25}) checkWorldJacobians(tm, target_, worldPoint(x, y, 2.0));
  }
}

// RsFrame::w_dot (the rows' rotation to second order): the solution satisfies the constraint with the
// rows' poses of rsPoseAt, which agree with exp(xi t + (0; w_dot t^2 / 2)) T0 to O(t^3), the shift is
// the size the angular acceleration predicts, and every Jacobian matches numeric differences.
TEST_F(RsProjectionTest, AngularAccelerationTakesTheRowsToSecondOrder) {
  RsFrame f = target_;
  f.w_dot = Vec3(-9.0, 15.0, 25.0);
  const RowTiming tm = RowTiming::rolling(timing_.y0, 5e-5, true);
  const double t_edge = tm.rowTime(0.0);
  Vec6 xi2 = f.xi * t_edge;
  xi2.tail<3>() += 0.5 * t_edge * t_edge * f.w_dot;
  const SE3d T_exact = SE3d::exp(xi2) * f.T_c_w0;
  const SE3d T_model = rsPoseAt(f, t_edge);
  const double second_order = 0.5 * t_edge * t_edge * f.w_dot.norm();  // ~6e-4 rad here
  const double third_order = f.w_dot.norm() * f.xi.norm() * std::pow(std::abs(t_edge), 3);
  EXPECT_LT((T_exact.inverse() * T_model).log().norm(), third_order);
  EXPECT_LT(third_order, 0.05 * second_order);
  EXPECT_GT((T_exact.inverse() * SE3d::exp(f.xi * t_edge) * f.T_c_w0).log().norm(), 0.9 * second_order);
  double max_shift = 0.0;
  for (double y : {-0.4, 0.0, 0.35}) {
    for (double x : {-0.5, 0.25}) {
      const Vec3 X = worldPoint(x, y, 2.0);
      const RsProjection r = projectRollingShutter(*cam_, tm, f, X, exact());
      ASSERT_TRUE(r.valid);
      Vec2 uv;
      ASSERT_TRUE(cam_->project(Vec3(rsPoseAt(f, r.t_s) * X), uv));
      EXPECT_LT((uv - r.uv).norm(), 1e-8);
      EXPECT_NEAR(r.t_s, tm.rowTime(r.uv.y()), 1e-9);
      max_shift = std::max(max_shift, (r.uv - projectRollingShutter(*cam_, tm, target_, X, exact()).uv).norm());
      checkWorldJacobians(tm, f, X);
    }
  }
  // At the outer rows (|t| ~ 6 ms) w_dot t^2 / 2 is ~0.6 mrad: ~0.15 px at f = 250.
  EXPECT_GT(max_shift, 0.05);
  EXPECT_LT(max_shift, 0.5);
}

TEST_F(RsProjectionTest, JacobiansAtZeroLineDelay) {
  // A rolling shutter whose delay is (still) 0: the pixel is the global one, but d uv / d line_delay is
  // not 0, so the delay can be estimated starting from 0.
  const RowTiming tm = RowTiming::rolling(timing_.y0, 0.0, false);
  const Vec3 X = worldPoint(0.3, 0.4, 2.0);
  const RsProjection r = projectRollingShutter(*cam_, tm, target_, X);
  EXPECT_EQ(r.iterations, 1);
  EXPECT_GT(r.d_uv_d_line_delay.norm(), 1.0);
  checkWorldJacobians(tm, target_, X);
}

TEST_F(RsProjectionTest, JacobiansAtTheImageBorder) {
  // Points whose projection lands on the border rows/columns (found by inverting the GS pixel).
  for (const Vec2& px : {Vec2(0.0, 0.0), Vec2(319.0, 255.0), Vec2(0.0, 255.0), Vec2(160.0, 0.0)}) {
    Vec3 b;
    ASSERT_TRUE(cam_->unproject(px, b));
    const Vec3 X = target_.T_c_w0.inverse() * Vec3(b * 2.0);
    const RsProjection r = projectRollingShutter(*cam_, timing_, target_, X);
    EXPECT_LT((r.uv - px).norm(), 30.0);
    checkWorldJacobians(timing_, target_, X);
  }
}

TEST_F(RsProjectionTest, DepthNearZero) {
  // Just in front of min_depth (1 mm): valid, Jacobians large but right. Behind it: invalid.
  RsFrame still = target_;
  still.xi.setZero();
  const Vec3 near = target_.T_c_w0.inverse() * Vec3(1e-4, -2e-4, 5e-3);
  checkWorldJacobians(timing_, still, near, 1e-5);
  checkWorldJacobians(timing_, target_, near, 1e-5);
  const Vec3 too_near = target_.T_c_w0.inverse() * Vec3(0.0, 0.0, 5e-4);
  EXPECT_FALSE(projectRollingShutter(*cam_, timing_, still, too_near).valid);
  const Vec3 behind = target_.T_c_w0.inverse() * Vec3(0.1, 0.1, -1.0);
  const RsProjection r = projectRollingShutter(*cam_, timing_, target_, behind);
  EXPECT_FALSE(r.valid);
  EXPECT_FALSE(r.converged);
}

TEST_F(RsProjectionTest, LargeTwists) {
  RsFrame f = target_;
  f.xi << 3.0, -2.0, 1.0, 2.0, -3.0, 1.5;
  const RowTiming tm = RowTiming::rolling(timing_.y0, 5e-5, true);
  for (double y : {-0.4, 0.0, 0.4}) checkWorldJacobians(tm, f, worldPoint(0.2, y, 1.5));
}

TEST_F(RsProjectionTest, SingularOrWildMotionStopsAndReportsFailure) {
  // Rotation about x moving the centre pixel down exactly as fast as the readout: 1 - a_y = 0.
  RsFrame f = target_;
  const RowTiming tm = RowTiming::rolling(timing_.y0, 5e-5, true);
  f.xi.setZero();
  f.xi[3] = -1.0 / (245.0 * 5e-5);
  const Vec3 X = target_.T_c_w0.inverse() * Vec3(0.0, 0.0, 2.0);
  const RsProjection r = projectRollingShutter(*cam_, tm, f, X);
  EXPECT_FALSE(r.valid);
  EXPECT_LE(r.iterations, RsProjectionOptions().max_iterations);
  // Absurd twists: the iteration ends within its budget, whatever it finds, and says so.
  std::mt19937 rng(3);
  std::normal_distribution<double> g(0.0, 2000.0);
  int failures = 0;
  for (int i = 0; i < 20; ++i) {
    RsFrame w = target_;
    for (int k = 0; k < 6; ++k) w.xi[k] = g(rng);
    const RsProjection q = projectRollingShutter(*cam_, tm, w, worldPoint(0.1, 0.2, 2.0));
    EXPECT_LE(q.iterations, RsProjectionOptions().max_iterations);
    if (q.valid) {
      Vec2 uv;
      ASSERT_TRUE(cam_->project(Vec3(SE3d::exp(w.xi * q.t_s) * (w.T_c_w0 * worldPoint(0.1, 0.2, 2.0))), uv));
      EXPECT_LT((uv - q.uv).norm(), 1e-5) << "a valid result satisfies the constraint";
    } else {
      ++failures;
    }
  }
  EXPECT_GT(failures, 0);
}

// TwistExp (rs_projection.h) is exp(xi t) of rsvio/lie/se3.h at every row time: rotation, translation and
// the point it moves, on the series branch (rolling-shutter angles, ~0.01 rad), on the trigonometric one
// (above 1 rad), for negative t (host rows above y0), and exactly the identity for a zero twist or
// t = 0. Held to 1e-14 against SE3d::exp, so a dropped or mis-scaled term of R or p fails it.
TEST(TwistExpTest, IsTheSe3ExponentialAlongTheRows) {
  const Vec6 twists[3] = {(Vec6() << 0.6, -0.2, 0.3, 0.4, -0.5, 0.2).finished(),
                          (Vec6() << 1.5, 0.7, -2.0, 0.9, 1.1, -0.6).finished(),
                          (Vec6() << 0.3, 0.1, 0.0, 0.0, 0.0, 0.0).finished()};
  const Vec3 X(0.4, -1.2, 5.0);
  for (const Vec6& xi : twists) {
    const TwistExp ex(xi);
    for (double t : {-0.015, -1e-4, 3e-6, 0.012, 0.8, 2.0}) {
      const SE3d E = SE3d::exp(xi * t);
      Mat3 R;
      Vec3 p;
      ex.at(t, R, p);
      EXPECT_LT((R - E.rotationMatrix()).norm(), 1e-14) << "t " << t;
      EXPECT_LT((p - E.translation()).norm(), 1e-14 * (1.0 + E.translation().norm())) << "t " << t;
      EXPECT_LT((ex.rotation(t) - E.rotationMatrix()).norm(), 1e-14) << "t " << t;
      EXPECT_LT((ex.apply(t, X) - E * X).norm(), 1e-13) << "t " << t;
    }
  }
  Mat3 R;
  Vec3 p;
  TwistExp(Vec6::Zero()).at(0.01, R, p);
  EXPECT_EQ(R, Mat3::Identity());
  EXPECT_EQ(p, Vec3::Zero());
  TwistExp(twists[0]).at(0.0, R, p);
  EXPECT_EQ(R, Mat3::Identity());
  EXPECT_EQ(p, Vec3::Zero());
}

// The rolling-shutter Jacobian's factor [I, -[p]x] Jl(xi t) from the per-twist products: SE3's left
// Jacobian at xi t, each 3x3 block against its own scale (J, and Q - [p]x J), over the rows' times and
// beyond, the series region (|w t| small) included; zero twist or t = 0 exactly [I, -[p]x].
TEST(TwistExpTest, LeftActionTimesLeftJacobianIsSe3sAlongTheRows) {
  const Vec6 twists[3] = {(Vec6() << 0.6, -0.2, 0.3, 0.4, -0.5, 0.2).finished(),
                          (Vec6() << 1.5, 0.7, -2.0, 0.9, 1.1, -0.6).finished(),
                          (Vec6() << 0.3, 0.1, 0.0, 1e-9, 0.0, 0.0).finished()};
  const Vec3 p(0.4, -1.2, 5.0);
  Eigen::Matrix<double, 3, 6> A;
  A.leftCols<3>().setIdentity();
  A.rightCols<3>() = -SO3d::hat(p);
  for (const Vec6& xi : twists) {
    const TwistExp ex(xi);
    for (double t : {-0.015, -1e-4, 3e-6, 0.012, 0.8, 2.0}) {
      const Eigen::Matrix<double, 3, 6> ref = A * SE3d::leftJacobian(xi * t);
      const Eigen::Matrix<double, 3, 6> got = ex.dLeftActionTimesJl(t, p);
      EXPECT_LT((got.leftCols<3>() - ref.leftCols<3>()).norm(), 1e-14 * ref.leftCols<3>().norm()) << "J, t " << t;
      EXPECT_LT((got.rightCols<3>() - ref.rightCols<3>()).norm(), 1e-13 * ref.rightCols<3>().norm())
          << "Q - [p]x J, t " << t;
    }
  }
  EXPECT_EQ(TwistExp(Vec6::Zero()).dLeftActionTimesJl(0.01, p), A);
  EXPECT_EQ(TwistExp(twists[0]).dLeftActionTimesJl(0.0, p), A);
}

}  // namespace
}  // namespace rsvio::test
