// The simulated trajectory: analytic derivatives against numeric differences, Table I presets, bounds,
// seeds.
#include <gtest/gtest.h>

#include "rsvio/lie/so3.h"
#include "rsvio/sim/rng.h"
#include "rsvio/sim/trajectory.h"
#include "sim_test_util.h"
#include "support/numeric_jacobian.h"

namespace rsvio::sim {
namespace {

using rsvio::test::numericJacobian;
using rsvio::test::rightMinus;
using rsvio::test::vectorPlus;

SimTrajectory fastTrajectory(uint64_t seed) {
  MotionSpec spec;
  spec.duration_s = 6.0;
  spec.mean_speed_m_s = 1.0;
  spec.mean_rot_speed_deg_s = 137.0;
  spec.mean_accel_m_s2 = 3.8;
  spec.mean_rot_accel_deg_s2 = 600.0;
  std::mt19937_64 rng = makeStream(seed, "trajectory");
  return SimTrajectory::generate(spec, rng);
}

TEST(SimTrajectory, DerivativesMatchNumericDifferences) {
  const SimTrajectory tr = fastTrajectory(3);
  for (double t : {0.05, 1.3, 2.71, 4.4, 5.9}) {
    const BodyState s = tr.state(t);
    const auto pos = [&](double x) { return Vec3(tr.state(x).p_W_B); };
    const auto vel = [&](double x) { return Vec3(tr.state(x).v_W); };
    const auto omega = [&](double x) { return Vec3(tr.state(x).omega_B); };
    const auto rot = [&](double x) { return SO3d(tr.state(x).q_W_B.normalized()); };
    EXPECT_JACOBIAN_NEAR(s.v_W, numericJacobian(pos, t, vectorPlus, 1), 1e-6) << "t = " << t;
    EXPECT_JACOBIAN_NEAR(s.a_W, numericJacobian(vel, t, vectorPlus, 1), 1e-6) << "t = " << t;
    // R' = R [omega_B]x: omega_B is the derivative in the right chart.
    EXPECT_JACOBIAN_NEAR(s.omega_B, numericJacobian(rot, t, vectorPlus, rightMinus<SO3d>, 1), 1e-6) << "t = " << t;
    EXPECT_JACOBIAN_NEAR(s.alpha_B, numericJacobian(omega, t, vectorPlus, 1), 1e-5) << "t = " << t;
  }
}

TEST(SimTrajectory, SameSeedSameTrajectoryOtherSeedOther) {
  const SimTrajectory a = fastTrajectory(5), b = fastTrajectory(5), c = fastTrajectory(6);
  for (double t : {0.0, 1.0, 3.3}) {
    EXPECT_EQ(a.state(t).p_W_B, b.state(t).p_W_B);
    EXPECT_EQ(a.state(t).q_W_B.coeffs(), b.state(t).q_W_B.coeffs());
    EXPECT_GT((a.state(t).p_W_B - c.state(t).p_W_B).norm(), 1e-3);
  }
}

// The ten paper-like sequences hit the mean statistics of the paper's Table I, stay inside the room
// (away from the walls) and inside the tilt limits.
TEST(SimTrajectory, TenSequencesFollowTableI) {
  const double table[10][6] = {{40, 46, 1.1, 62, 3.2, 233}, {27, 37, 1.4, 73, 4.1, 271}, {50, 44, 0.9, 56, 2.3, 220},
                               {38, 30, 0.8, 39, 1.1, 148}, {85, 57, 0.7, 43, 0.8, 167}, {43, 51, 1.2, 50, 2.6, 252},
                               {39, 45, 1.1, 92, 2.7, 148}, {53, 46, 0.9, 91, 1.8, 103}, {45, 46, 1.0, 137, 3.8, 539},
                               {54, 41, 0.7, 116, 2.1, 605}};
  for (int i = 0; i < 10; ++i) {
    char name[16];
    std::snprintf(name, sizeof(name), "seq%02d", i + 1);
    const SimSettings s = simSettings(test::tinyConfig(name));
    EXPECT_EQ(s.motion.duration_s, table[i][0]) << name;
    std::mt19937_64 rng = makeStream(s.seed, "trajectory");
    const SimTrajectory tr = SimTrajectory::generate(s.motion, rng);
    const MotionStats st = tr.stats(100.0);
    EXPECT_NEAR(st.mean_speed_m_s, table[i][2], 0.03 * table[i][2]) << name;
    EXPECT_NEAR(st.mean_rot_speed_deg_s, table[i][3], 0.03 * table[i][3]) << name;
    EXPECT_NEAR(st.mean_accel_m_s2, table[i][4], 0.03 * table[i][4]) << name;
    EXPECT_NEAR(st.mean_rot_accel_deg_s2, table[i][5], 0.03 * table[i][5]) << name;
    EXPECT_NEAR(st.path_length_m, table[i][1], 0.2 * table[i][1]) << name;
    // Inside the allowed box: at least wall_clearance_m from every wall.
    EXPECT_TRUE((st.min_position - s.motion.box_min).minCoeff() > -0.02) << name << " min " << st.min_position.transpose();
    EXPECT_TRUE((s.motion.box_max - st.max_position).minCoeff() > -0.02) << name << " max " << st.max_position.transpose();
    EXPECT_LE(st.max_abs_pitch_deg, s.motion.max_pitch_deg + 0.5) << name;
    EXPECT_LE(st.max_abs_roll_deg, s.motion.max_roll_deg + 0.5) << name;
  }
}

TEST(SimTrajectory, ImpossibleTargetsAreConfigErrors) {
  MotionSpec spec;
  spec.mean_speed_m_s = 5.0;  // 5 m/s for 20 s in a 6.6 x 4.6 m box with 0.25 m/s^2: impossible
  spec.mean_accel_m_s2 = 0.25;
  std::mt19937_64 rng = makeStream(1, "trajectory");
  try {
    SimTrajectory::generate(spec, rng);
    FAIL() << "expected a ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("motion.mean_", 0), 0u) << e.what();
  }
}

}  // namespace
}  // namespace rsvio::sim
