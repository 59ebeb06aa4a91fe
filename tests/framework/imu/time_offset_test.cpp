// Camera-IMU time offset (t_imu = t_cam + offset): the preintegration's first-order offset model
// against re-preintegration over shifted windows, and the offset recovered by Gauss-Newton on IMU factors.
#include <gtest/gtest.h>

#include <random>

#include "framework/imu/imu_test_data.h"
#include "rsvio/imu/imu_factor.h"
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

// d(dR, dv, dp)/d(offset) from the measurements at the window ends (preintegration.h) equals the
// derivative of re-preintegrating over [t_i + o, t_j + o]. The analytic form is the continuous-time
// derivative; the midpoint rule's own derivative differs by O(dt^2): measured 1e-6 (R), 2e-6 (v) and
// 9e-6 (p) relative at 200 Hz, hence the tolerance 1e-4 (a wrong sign or a missing term is off by O(1)).
TEST(TimeOffset, FirstOrderModelMatchesShiftedReintegration) {
  const AnalyticTrajectory tr = AnalyticTrajectory::medium();
  test::ImuSimOptions o;
  o.bias.gyro = Vec3(0.01, 0.02, -0.01);
  o.bias.accel = Vec3(0.1, -0.1, 0.05);
  const ImuBuffer buf = bufferOf(test::simulateImu(tr, 0.0, 2.0, o));
  const int64_t ti = secToNs(0.5123), tj = secToNs(1.0456);
  auto pre = [&](double off) { return ImuPreintegration::fromBuffer(buf, ti, tj, o.noise, o.bias, off); };
  const ImuPreintegration p0 = pre(0.0);
  const double h = 1e-4;  // exactly 100000 ns, so the shifted windows are exact
  const auto num_R = numericJacobian([&](double off) { return pre(off).deltaR(); }, 0.0, test::vectorPlus,
                                     test::rightMinus<SO3d>, 1, h);
  const auto num_v = numericJacobian([&](double off) { return pre(off).deltaV(); }, 0.0, test::vectorPlus, 1, h);
  const auto num_p = numericJacobian([&](double off) { return pre(off).deltaP(); }, 0.0, test::vectorPlus, 1, h);
  std::printf("offset derivative, relative error: R %.1e v %.1e p %.1e\n",
              (p0.d_R_d_offset() - num_R).norm() / num_R.norm(), (p0.d_v_d_offset() - num_v).norm() / num_v.norm(),
              (p0.d_p_d_offset() - num_p).norm() / num_p.norm());
  EXPECT_JACOBIAN_NEAR_TOL(p0.d_R_d_offset(), num_R, 1e-4, 1e-4 * num_R.norm());
  EXPECT_JACOBIAN_NEAR_TOL(p0.d_v_d_offset(), num_v, 1e-4, 1e-4 * num_v.norm());
  EXPECT_JACOBIAN_NEAR_TOL(p0.d_p_d_offset(), num_p, 1e-4, 1e-4 * num_p.norm());
  // The corrected measurement follows a shifted re-preintegration for a 3 ms offset to second order.
  const ImuPreintegration::Delta c = p0.corrected(o.bias, 0.003);
  const ImuPreintegration p3 = pre(0.003);
  EXPECT_LT((c.v - p3.deltaV()).norm(), 0.05 * (p0.deltaV() - p3.deltaV()).norm());
  EXPECT_LT((c.R.inverse() * p3.deltaR()).log().norm(), 0.05 * (p0.deltaR().inverse() * p3.deltaR()).log().norm());
}

// IMU samples stamped with a clock 8 ms ahead of the camera's (t_imu = t_cam + 0.008): a scalar
// Gauss-Newton on the IMU factors (true states as from vision, noisy IMU) recovers the offset; the
// preintegration is redone at each new estimate, as an estimator would once the offset moved.
TEST(TimeOffset, GaussNewtonRecoversOffset) {
  const AnalyticTrajectory tr = AnalyticTrajectory::medium();
  const double true_offset = 0.008;
  test::ImuSimOptions o;
  o.add_noise = true;  // noise-free data give 7.9998 ms
  o.t0_ns = secToNs(true_offset);  // sample k: IMU stamp k/rate + offset, truth at camera time k/rate
  std::mt19937_64 rng(4);
  const ImuBuffer buf = bufferOf(test::simulateImu(tr, 0.0, 4.0, o, &rng));
  std::vector<double> t;
  for (double s = 0.2; s < 3.8; s += 0.3) t.push_back(s);
  double offset = 0.0;
  for (int it = 0; it < 4; ++it) {
    double H = 0.0, g = 0.0;
    for (size_t k = 0; k + 1 < t.size(); ++k) {
      const ImuFactor f(ImuPreintegration::fromBuffer(buf, secToNs(t[k]), secToNs(t[k + 1]), o.noise, ImuBias{}, offset));
      ImuFactorJacobians J;
      const Vec15 r = f.residual(tr.state(t[k]), tr.state(t[k + 1]), offset, &J);
      const Mat15 W = f.information();
      H += J.d_res_d_offset.dot(W * J.d_res_d_offset);
      g += J.d_res_d_offset.dot(W * r);
    }
    offset -= g / H;
  }
  std::printf("time offset: estimated %.4f ms, true %.4f ms\n", offset * 1e3, true_offset * 1e3);
  EXPECT_NEAR(offset, true_offset, 2e-4);
}

}  // namespace
}  // namespace rsvio
