// IMU synthesis: integrating the noise-free IMU reproduces the ground truth; biases and noise are what
// the effects' parameters say, and the ground truth's bias columns agree with the measurements.
#include <gtest/gtest.h>

#include <cmath>

#include "sim_test_util.h"

namespace rsvio::sim {
namespace {

using test::effect;
using test::withEffects;

struct NavState {
  Eigen::Quaterniond q;
  Vec3 v, p;
};

NavState derivative(const NavState& x, const Vec3& gyro, const Vec3& accel) {
  // q' = q (0, omega) / 2,  v' = R f + g,  p' = v  (q' stored in q's coefficients).
  NavState d;
  const Eigen::Quaterniond w(0.0, gyro.x(), gyro.y(), gyro.z());
  d.q.coeffs() = 0.5 * (x.q * w).coeffs();
  d.v = x.q * accel + Vec3(0, 0, -kGravity);
  d.p = x.v;
  return d;
}

NavState add(const NavState& x, const NavState& d, double h) {
  NavState y;
  y.q.coeffs() = x.q.coeffs() + h * d.q.coeffs();
  y.v = x.v + h * d.v;
  y.p = x.p + h * d.p;
  return y;
}

// Classic RK4 between samples; the mid-step measurement is the cubic through the four nearest samples.
NavState integrate(const std::vector<ImuSample>& m, size_t k0, size_t k1, NavState x) {
  for (size_t k = k0; k < k1; ++k) {
    const double h = static_cast<double>(m[k + 1].t_ns - m[k].t_ns) * 1e-9;
    const size_t a = k > 0 ? k - 1 : k, b = std::min(k + 2, m.size() - 1);
    const Vec3 g_mid = (-m[a].gyro_rad_s + 9 * m[k].gyro_rad_s + 9 * m[k + 1].gyro_rad_s - m[b].gyro_rad_s) / 16.0;
    const Vec3 f_mid = (-m[a].accel_m_s2 + 9 * m[k].accel_m_s2 + 9 * m[k + 1].accel_m_s2 - m[b].accel_m_s2) / 16.0;
    const NavState k1s = derivative(x, m[k].gyro_rad_s, m[k].accel_m_s2);
    const NavState k2s = derivative(add(x, k1s, h / 2), g_mid, f_mid);
    const NavState k3s = derivative(add(x, k2s, h / 2), g_mid, f_mid);
    const NavState k4s = derivative(add(x, k3s, h), m[k + 1].gyro_rad_s, m[k + 1].accel_m_s2);
    x.q.coeffs() += h / 6 * (k1s.q.coeffs() + 2 * k2s.q.coeffs() + 2 * k3s.q.coeffs() + k4s.q.coeffs());
    x.q.normalize();
    x.v += h / 6 * (k1s.v + 2 * k2s.v + 2 * k3s.v + k4s.v);
    x.p += h / 6 * (k1s.p + 2 * k2s.p + 2 * k3s.p + k4s.p);
  }
  return x;
}

void expectIntegrationMatches(const Simulator& sim) {
  const auto& imu = sim.imu();
  const auto& gt = sim.groundTruth();
  ASSERT_EQ(imu.size(), gt.size());
  const size_t steps = static_cast<size_t>(2.0 * sim.sensor().imu.rate_hz);  // 2 s
  ASSERT_GT(imu.size(), steps + 10);
  for (size_t k0 : {size_t(0), imu.size() - 1 - steps}) {
    NavState x{gt[k0].q_W_B, gt[k0].v_W, gt[k0].p_W_B};
    const size_t k1 = k0 + steps;
    const NavState y = integrate(imu, k0, k1, x);
    const double pos_err = (y.p - gt[k1].p_W_B).norm();
    const double rot_err_deg = y.q.angularDistance(gt[k1].q_W_B) * 180.0 / M_PI;
    EXPECT_LT(pos_err, 1e-3) << "start sample " << k0;
    EXPECT_LT(rot_err_deg, 0.05) << "start sample " << k0;
    EXPECT_LT((y.v - gt[k1].v_W).norm(), 1e-3);
    // Not trivially small: the body really moved and turned.
    EXPECT_GT((gt[k1].p_W_B - gt[k0].p_W_B).norm() + gt[k1].q_W_B.angularDistance(gt[k0].q_W_B), 0.5);
  }
}

TEST(SimImu, NoiseFreeIntegrationReproducesGroundTruth) {
  Simulator sim(withEffects("tiny_gs", nlohmann::json::object()), test::host());
  expectIntegrationMatches(sim);
}

TEST(SimImu, NoiseFreeIntegrationReproducesGroundTruthUnderFastMotion) {
  Simulator sim(withEffects("tiny_gs", nlohmann::json::object(),
                            {"motion.mean_speed_m_s=1.0", "motion.mean_rot_speed_deg_s=137", "motion.mean_accel_m_s2=3.8",
                             "motion.mean_rot_accel_deg_s2=605"}),
                test::host());
  expectIntegrationMatches(sim);
}

TEST(SimImu, StampsAndGravity) {
  Simulator sim(withEffects("tiny_gs", nlohmann::json::object()), test::host());
  const auto& imu = sim.imu();
  EXPECT_EQ(imu.front().t_ns, sim.sensor().start_ns);
  for (size_t k = 1; k < imu.size(); ++k) ASSERT_EQ(imu[k].t_ns - imu[k - 1].t_ns, 5000000);
  // The specific force is R^T (a - g): its world-frame version minus a is +9.81 up.
  const auto& gt = sim.groundTruth();
  const BodyState s = sim.trajectory().state(1.0);
  const size_t k = 200;
  EXPECT_NEAR(((gt[k].q_W_B * imu[k].accel_m_s2) - s.a_W - Vec3(0, 0, kGravity)).norm(), 0.0, 1e-9);
}

TEST(SimImu, ConstantBiasShowsInMeasurementsAndGroundTruth) {
  const Vec3 bg(0.01, -0.02, 0.03), ba(0.2, -0.1, 0.05);
  Simulator ideal(withEffects("tiny_gs", nlohmann::json::object()), test::host());
  Simulator biased(withEffects("tiny_gs", {{"bias", effect("effect.imu_bias", {{"gyro_bias_rad_s", {0.01, -0.02, 0.03}},
                                                                              {"accel_bias_m_s2", {0.2, -0.1, 0.05}}})}}),
                   test::host());
  for (size_t k = 0; k < ideal.imu().size(); k += 37) {
    EXPECT_NEAR((biased.imu()[k].gyro_rad_s - ideal.imu()[k].gyro_rad_s - bg).norm(), 0.0, 1e-12);
    EXPECT_NEAR((biased.imu()[k].accel_m_s2 - ideal.imu()[k].accel_m_s2 - ba).norm(), 0.0, 1e-12);
    EXPECT_EQ(biased.groundTruth()[k].gyro_bias, bg);
    EXPECT_EQ(biased.groundTruth()[k].accel_bias, ba);
    EXPECT_EQ(ideal.groundTruth()[k].gyro_bias, Vec3::Zero());
  }
}

// White noise std = density * sqrt(rate); bias increments std = random_walk * sqrt(dt); density_scale
// scales both. The ground truth's bias columns are the walk.
TEST(SimImu, NoiseHasTheDensitiesOfTheImuSection) {
  for (double scale : {1.0, 3.0}) {
    const std::vector<std::string> sets = {"motion.duration_s=20", "imu.gyroscope_noise_density=0.001",
                                           "imu.accelerometer_noise_density=0.01", "imu.gyroscope_random_walk=0.0005",
                                           "imu.accelerometer_random_walk=0.004"};
    Simulator ideal(withEffects("tiny_gs", nlohmann::json::object(), sets), test::host());
    Simulator noisy(withEffects("tiny_gs", {{"imu_noise", effect("effect.imu_noise", {{"density_scale", scale}})}}, sets),
                    test::host());
    const auto& a = ideal.imu();
    const auto& b = noisy.imu();
    const auto& gt = noisy.groundTruth();
    double wg = 0, wa = 0, dg = 0, da = 0;
    const size_t n = a.size();
    for (size_t k = 0; k < n; ++k) {
      wg += (b[k].gyro_rad_s - a[k].gyro_rad_s - gt[k].gyro_bias).squaredNorm();
      wa += (b[k].accel_m_s2 - a[k].accel_m_s2 - gt[k].accel_bias).squaredNorm();
      if (k > 0) {
        dg += (gt[k].gyro_bias - gt[k - 1].gyro_bias).squaredNorm();
        da += (gt[k].accel_bias - gt[k - 1].accel_bias).squaredNorm();
      }
    }
    const double rate = 200.0;
    EXPECT_NEAR(std::sqrt(wg / (3 * n)), scale * 0.001 * std::sqrt(rate), 0.05 * scale * 0.001 * std::sqrt(rate));
    EXPECT_NEAR(std::sqrt(wa / (3 * n)), scale * 0.01 * std::sqrt(rate), 0.05 * scale * 0.01 * std::sqrt(rate));
    EXPECT_NEAR(std::sqrt(dg / (3 * (n - 1))), scale * 0.0005 / std::sqrt(rate), 0.05 * scale * 0.0005 / std::sqrt(rate));
    EXPECT_NEAR(std::sqrt(da / (3 * (n - 1))), scale * 0.004 / std::sqrt(rate), 0.05 * scale * 0.004 / std::sqrt(rate));
    EXPECT_EQ(gt.front().gyro_bias, Vec3::Zero());
  }
}

}  // namespace
}  // namespace rsvio::sim
