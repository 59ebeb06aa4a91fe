// Photometric residual of a point observation: every Jacobian (target and host pose, target and host
// twist, inverse depth, affine brightness of host and target, line delay) against numeric differences
// through the shared helper, on an analytic image (exact intensities and gradients) with a rolling
// shutter; plus the pattern warp against exact per-pixel projection, and the weights.
#include <gtest/gtest.h>

#include "rsvio/photometric/point_observation.h"
#include "support/numeric_jacobian.h"
#include "test_camera.h"

namespace rsvio {
namespace {

using test::numericJacobian;

// A smooth image with exact gradients: the sampler the residual templates accept.
struct AnalyticImage {
  double phase = 0.0;
  int w = 320, h = 256;
  double f(double u, double v) const {
    return 120.0 + 40.0 * std::sin(0.11 * u + 0.3 + phase) * std::cos(0.07 * v) + 25.0 * std::sin(0.05 * u - 0.09 * v);
  }
  bool inside(float u, float v, float m) const { return u >= m && v >= m && u <= w - 1 - m && v <= h - 1 - m; }
  void sample(float uf, float vf, float* out) const {
    const double u = uf, v = vf;
    const double gx = 40.0 * 0.11 * std::cos(0.11 * u + 0.3 + phase) * std::cos(0.07 * v) + 25.0 * 0.05 * std::cos(0.05 * u - 0.09 * v);
    const double gy = -40.0 * 0.07 * std::sin(0.11 * u + 0.3 + phase) * std::sin(0.07 * v) - 25.0 * 0.09 * std::cos(0.05 * u - 0.09 * v);
    out[0] = static_cast<float>(f(u, v));
    out[1] = static_cast<float>(gx);
    out[2] = static_cast<float>(gy);
    out[3] = static_cast<float>(gx * gx + gy * gy);
  }
};

Vec6 twist(double tx, double ty, double tz, double rx, double ry, double rz) {
  Vec6 v;
  v << tx, ty, tz, rx, ry, rz;
  return v;
}

struct ObsSetup {
  test::PinholeK K;
  test::TestPinholeCamera camera{K};
  RowTiming timing = RowTiming::rolling(127.5, 40e-6, true);
  AnalyticImage host_img, target_img;
  ObservationFrames frames;
  std::vector<HostPoint> points;
  ResidualOptions opt;

  ObsSetup() {
    target_img.phase = 0.2;
    frames.host = RsFrame{SE3d::exp(twist(0.1, -0.05, 0.02, 0.03, -0.02, 0.01)), twist(0.4, 0.1, -0.2, 0.3, -0.5, 0.2)};
    frames.target = RsFrame{SE3d::exp(twist(0.05, 0.02, -0.15, 0.02, 0.04, -0.03)) * frames.host.T_c_w0,
                            twist(-0.3, 0.2, 0.5, -0.4, 0.6, 0.1)};
    frames.host_affine = AffineBrightness{0.1, 3.0};
    frames.target_affine = AffineBrightness{-0.05, -4.0};
    frames.exposure_ratio = 1.2;
    const ResidualOptions o;
    for (const Vec2& uv : {Vec2(60, 50), Vec2(200, 180), Vec2(150, 90), Vec2(250, 40)}) {
      HostPoint p;
      p.uv = uv;
      Eigen::Matrix3Xd b;
      std::vector<uint8_t> valid;
      std::vector<Jac32> J;
      camera.unproject(Eigen::Matrix2Xd(uv), b, valid, &J);
      p.bearing = b.col(0);
      p.d_bearing_d_uv = J[0];
      p.idepth = 0.25 + 0.001 * uv.x();
      for (int k = 0; k < kPatternSize; ++k) {
        float s[4];
        host_img.sample(static_cast<float>(uv.x() + kPattern[k][0]), static_cast<float>(uv.y() + kPattern[k][1]), s);
        p.pattern.color[k] = s[0];
        p.pattern.weight[k] = gradientWeight(s[3], 2500.f);
      }
      points.push_back(p);
    }
  }

  std::vector<Observation> evaluate(const ObservationFrames& fr, const std::vector<HostPoint>& pts,
                                    const std::vector<Eigen::Matrix2d>* warps, const RowTiming& t) const {
    std::vector<Observation> out;
    evaluateObservations(camera, t, fr, target_img, pts, opt, out, warps);
    return out;
  }
};

Eigen::Matrix<double, kPatternSize, 1> residualOf(const Observation& o) {
  Eigen::Matrix<double, kPatternSize, 1> r;
  for (int k = 0; k < kPatternSize; ++k) r[k] = o.res.r[k];
  return r;
}

// Float kernel: perturbations move p' by ~0.05-0.2 px; tolerance for float residuals.
constexpr double kRel = 3e-3;

::testing::AssertionResult near(const Eigen::MatrixXd& a, const Eigen::MatrixXd& n) {
  return test::jacobianNear(a, n, kRel, kRel * std::max(1.0, a.cwiseAbs().maxCoeff()));
}

TEST(PointObservation, AllJacobiansMatchNumericDifferences) {
  const ObsSetup s;
  const std::vector<Observation> base = s.evaluate(s.frames, s.points, nullptr, s.timing);
  std::vector<Eigen::Matrix2d> warps;
  for (const Observation& o : base) warps.push_back(o.warp);
  for (size_t i = 0; i < s.points.size(); ++i) {
    SCOPED_TRACE("point " + std::to_string(i));
    ASSERT_TRUE(base[i].valid);
    const ObservationJacobians J = observationJacobians(base[i], s.points[i], s.frames);
    auto r = [&](const ObservationFrames& fr, const std::vector<HostPoint>& pts, const RowTiming& t) {
      return residualOf(s.evaluate(fr, pts, &warps, t)[i]);
    };
    const Eigen::MatrixXd n_Tt = numericJacobian(
        [&](const SE3d& T) { ObservationFrames f = s.frames; f.target.T_c_w0 = T; return r(f, s.points, s.timing); },
        s.frames.target.T_c_w0, test::leftPlus<SE3d>, 6, 2e-4);
    EXPECT_TRUE(near(J.d_r_d_T_target, n_Tt)) << "target pose";
    const Eigen::MatrixXd n_Th = numericJacobian(
        [&](const SE3d& T) { ObservationFrames f = s.frames; f.host.T_c_w0 = T; return r(f, s.points, s.timing); },
        s.frames.host.T_c_w0, test::leftPlus<SE3d>, 6, 2e-4);
    EXPECT_TRUE(near(J.d_r_d_T_host, n_Th)) << "host pose";
    const Eigen::MatrixXd n_xt = numericJacobian(
        [&](const Vec6& xi) { ObservationFrames f = s.frames; f.target.xi = xi; return r(f, s.points, s.timing); },
        s.frames.target.xi, test::vectorPlus, 6, 2e-2);
    EXPECT_TRUE(near(J.d_r_d_xi_target, n_xt)) << "target twist";
    const Eigen::MatrixXd n_xh = numericJacobian(
        [&](const Vec6& xi) { ObservationFrames f = s.frames; f.host.xi = xi; return r(f, s.points, s.timing); },
        s.frames.host.xi, test::vectorPlus, 6, 2e-2);
    EXPECT_TRUE(near(J.d_r_d_xi_host, n_xh)) << "host twist";
    const Eigen::MatrixXd n_id = numericJacobian(
        [&](double rho) { std::vector<HostPoint> p = s.points; p[i].idepth = rho; return r(s.frames, p, s.timing); },
        s.points[i].idepth, test::vectorPlus, 1, 1e-3);
    EXPECT_TRUE(near(J.d_r_d_idepth, n_id)) << "inverse depth";
    const Eigen::MatrixXd n_abh = numericJacobian(
        [&](const Eigen::Vector2d& ab) {
          ObservationFrames f = s.frames;
          f.host_affine = AffineBrightness{ab[0], ab[1]};
          return r(f, s.points, s.timing);
        },
        Eigen::Vector2d(s.frames.host_affine.a, s.frames.host_affine.b), test::vectorPlus, 2, 1e-3);
    EXPECT_TRUE(near(J.d_r_d_ab_host, n_abh)) << "host affine";
    const Eigen::MatrixXd n_abt = numericJacobian(
        [&](const Eigen::Vector2d& ab) {
          ObservationFrames f = s.frames;
          f.target_affine = AffineBrightness{ab[0], ab[1]};
          return r(f, s.points, s.timing);
        },
        Eigen::Vector2d(s.frames.target_affine.a, s.frames.target_affine.b), test::vectorPlus, 2, 1e-3);
    EXPECT_TRUE(near(J.d_r_d_ab_target, n_abt)) << "target affine";
    const Eigen::MatrixXd n_ld = numericJacobian(
        [&](double ld) { return r(s.frames, s.points, RowTiming::rolling(s.timing.y0, ld, true)); },
        s.timing.line_delay_s, test::vectorPlus, 1, 2e-6);
    EXPECT_TRUE(near(J.d_r_d_line_delay, n_ld)) << "line delay";
  }
}

TEST(PointObservation, GlobalShutterJacobiansToo) {
  // A global shutter takes a faster path (no RS solve); same contract, same checks.
  const ObsSetup s;
  const RowTiming gs = RowTiming::global(127.5);
  const std::vector<Observation> base = s.evaluate(s.frames, s.points, nullptr, gs);
  const std::vector<Observation> rs_zero = s.evaluate(s.frames, s.points, nullptr, RowTiming::rolling(127.5, 0.0, true));
  std::vector<Eigen::Matrix2d> warps;
  for (const Observation& o : base) warps.push_back(o.warp);
  for (size_t i = 0; i < s.points.size(); ++i) {
    SCOPED_TRACE("point " + std::to_string(i));
    ASSERT_TRUE(base[i].valid);
    // Same geometry as the general RS path with a zero line delay.
    EXPECT_LT((base[i].proj.uv - rs_zero[i].proj.uv).norm(), 1e-9);
    EXPECT_TRUE(base[i].proj.d_uv_d_Th0.isApprox(rs_zero[i].proj.d_uv_d_Th0, 1e-9));
    EXPECT_TRUE(base[i].warp.isApprox(rs_zero[i].warp, 1e-9));
    const ObservationJacobians J = observationJacobians(base[i], s.points[i], s.frames);
    auto r = [&](const ObservationFrames& fr, const std::vector<HostPoint>& pts) {
      return residualOf(s.evaluate(fr, pts, &warps, gs)[i]);
    };
    const Eigen::MatrixXd n_Tt = numericJacobian(
        [&](const SE3d& T) { ObservationFrames f = s.frames; f.target.T_c_w0 = T; return r(f, s.points); },
        s.frames.target.T_c_w0, test::leftPlus<SE3d>, 6, 2e-4);
    EXPECT_TRUE(near(J.d_r_d_T_target, n_Tt)) << "target pose";
    const Eigen::MatrixXd n_Th = numericJacobian(
        [&](const SE3d& T) { ObservationFrames f = s.frames; f.host.T_c_w0 = T; return r(f, s.points); },
        s.frames.host.T_c_w0, test::leftPlus<SE3d>, 6, 2e-4);
    EXPECT_TRUE(near(J.d_r_d_T_host, n_Th)) << "host pose";
    const Eigen::MatrixXd n_id = numericJacobian(
        [&](double rho) { std::vector<HostPoint> p = s.points; p[i].idepth = rho; return r(s.frames, p); },
        s.points[i].idepth, test::vectorPlus, 1, 1e-3);
    EXPECT_TRUE(near(J.d_r_d_idepth, n_id)) << "inverse depth";
    EXPECT_TRUE(J.d_r_d_xi_target.isZero());  // a global shutter has no row time
    EXPECT_TRUE(J.d_r_d_xi_host.isZero());
    EXPECT_TRUE(J.d_r_d_line_delay.isZero());
  }
}

TEST(PointObservation, WarpPlacesThePatternWhereExactProjectionPutsIt) {
  const ObsSetup s;
  const std::vector<Observation> obs = s.evaluate(s.frames, s.points, nullptr, s.timing);
  for (size_t i = 0; i < s.points.size(); ++i) {
    for (int k = 0; k < kPatternSize; ++k) {
      const Vec2 uv_h = s.points[i].uv + Vec2(kPattern[k][0], kPattern[k][1]);
      Vec3 b;
      ASSERT_TRUE(s.camera.unproject(uv_h, b));
      const RsHostProjection exact =
          projectRollingShutter(s.camera, s.timing, s.frames.host, s.frames.target, b, uv_h.y(), s.points[i].idepth);
      const Vec2 approx = obs[i].proj.uv + obs[i].warp * Vec2(kPattern[k][0], kPattern[k][1]);
      EXPECT_LT((exact.uv - approx).norm(), 0.02) << "point " << i << " pattern pixel " << k;
    }
  }
}

TEST(PointObservation, WeightsEnergyAndOutliers) {
  const ObsSetup s;
  std::vector<Observation> obs = s.evaluate(s.frames, s.points, nullptr, s.timing);
  const Observation& o = obs[0];
  const ResidualKernel k(s.opt);
  float energy = 0;
  for (int i = 0; i < kPatternSize; ++i) {
    const double wg = 0.5 * (s.points[0].pattern.weight[i] + gradientWeight(o.res.gx[i] * o.res.gx[i] + o.res.gy[i] * o.res.gy[i], k.c2));
    EXPECT_NEAR(o.res.wg2[i], wg * wg, 1e-6);
    EXPECT_NEAR(o.res.w[i], wg * wg * std::min(1.0, 9.0 / std::abs(o.res.r[i])), 1e-6);
    energy += o.res.wg2[i] * huberEnergy(o.res.r[i], 9.f);
  }
  EXPECT_NEAR(o.res.energy, energy, 1e-3);
  EXPECT_EQ(o.res.outlier, !(o.res.energy <= 12.0 * 12.0 * kPatternSize));
  // A brightness far off makes every observation an outlier.
  ObservationFrames f = s.frames;
  f.target_affine.b += 80.0;
  for (const Observation& x : s.evaluate(f, s.points, nullptr, s.timing)) EXPECT_TRUE(x.res.outlier);
  // Huber: quadratic inside the threshold, linear outside, continuous at it.
  EXPECT_FLOAT_EQ(huberEnergy(3.f, 9.f), 9.f);
  EXPECT_FLOAT_EQ(huberEnergy(-20.f, 9.f), 2.f * 9.f * 20.f - 81.f);
  EXPECT_FLOAT_EQ(huberEnergy(9.f, 9.f), 81.f);
  EXPECT_FLOAT_EQ(huberWeight(18.f, 9.f), 0.5f);
}

}  // namespace
}  // namespace rsvio
