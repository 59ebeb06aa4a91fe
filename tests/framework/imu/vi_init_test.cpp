// Visual-inertial initialisation (vi_init.h): ground-truth camera poses at an arbitrary scale and
// orientation of W_f, noisy biased IMU; scale, gravity, velocities and gyro bias are recovered on medium
// motion, and motion without acceleration is refused with a reason.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "framework/imu/imu_test_data.h"
#include "rsvio/imu/vi_init.h"

namespace rsvio {
namespace {

using test::AnalyticTrajectory;
using test::secToNs;

struct Scenario {
  AnalyticTrajectory tr;
  SE3d T_cm_i = test::defaultCameraFromImu();
  RxSO3d T_wm_wf = test::defaultMetricFromFree();  // truth: 2.5 m per unit, tilted
  test::ImuSimOptions o;
  ImuBuffer imu;
  std::vector<ViInitKeyframe> kfs;
  std::vector<double> t;

  Scenario(const AnalyticTrajectory& trajectory, int num_kf, double kf_period_s, uint64_t seed,
           double offset_s = 0.0)
      : tr(trajectory) {
    o.add_noise = true;
    o.bias.gyro = Vec3(0.008, -0.012, 0.01);
    o.bias.accel = Vec3(0.04, -0.03, 0.05);
    o.t0_ns = secToNs(offset_s);
    std::mt19937_64 rng(seed);
    for (const auto& s : test::simulateImu(tr, 0.0, 0.2 + num_kf * kf_period_s, o, &rng)) imu.add(s);
    for (int k = 0; k < num_kf; ++k) {
      const double tk = 0.1 + kf_period_s * k + 0.0013;  // keyframes off the IMU sample grid
      t.push_back(tk);
      kfs.push_back({secToNs(tk), test::cameraPoseAt(tr, tk, T_cm_i, T_wm_wf)});
    }
  }

  double gravityErrorDeg(const ViInitResult& r) const {
    const Vec3 est = r.T_wm_wf.so3().inverse() * Vec3(0, 0, -1);  // gravity direction in W_f
    const Vec3 tru = T_wm_wf.so3().inverse() * Vec3(0, 0, -1);
    return std::acos(std::clamp(est.dot(tru), -1.0, 1.0)) * 180.0 / M_PI;
  }
  double scaleError(const ViInitResult& r) const { return std::abs(r.T_wm_wf.scale() / T_wm_wf.scale() - 1.0); }
  // Velocities are in W_m, whose yaw about gravity is a gauge: compare in W_f axes, scaled.
  double maxVelocityError(const ViInitResult& r) const {
    double e = 0.0;
    for (size_t k = 0; k < t.size(); ++k) {
      const Vec3 v_true_wf = T_wm_wf.so3().inverse() * tr.velocity(t[k]);
      const Vec3 v_est_wf = r.T_wm_wf.so3().inverse() * r.velocities_wm[k];
      e = std::max(e, (v_est_wf - v_true_wf).norm());
    }
    return e;
  }
};

TEST(ViInit, RecoversScaleGravityVelocitiesAndGyroBiasOnMediumMotion) {
  for (uint64_t seed : {1u, 2u, 3u}) {
    Scenario sc(AnalyticTrajectory::medium(), 13, 0.25, seed);  // 3 s, keyframes at 4 Hz
    ViInitOptions linear_only;
    linear_only.refine_nonlinear = false;
    const ViInitResult lin = initializeVisualInertial(sc.kfs, sc.imu, sc.o.noise, sc.T_cm_i, 0.0, linear_only);
    const ViInitResult r = initializeVisualInertial(sc.kfs, sc.imu, sc.o.noise, sc.T_cm_i);
    ASSERT_TRUE(r.success) << r.status;
    ASSERT_TRUE(lin.success) << lin.status;
    std::printf("seed %d: %s\n  linear: scale err %.3f%% gravity err %.3f deg | refined: scale err %.3f%% gravity err "
                "%.3f deg, |v| err %.3f m/s, b_g err %.1e rad/s, b_a err %.3f m/s^2\n",
                static_cast<int>(seed), r.status.c_str(), 100 * sc.scaleError(lin), sc.gravityErrorDeg(lin),
                100 * sc.scaleError(r), sc.gravityErrorDeg(r), sc.maxVelocityError(r),
                (r.bias.gyro - sc.o.bias.gyro).norm(), (r.bias.accel - sc.o.bias.accel).norm());
    EXPECT_LT(sc.scaleError(r), 0.02);
    EXPECT_LT(sc.gravityErrorDeg(r), 1.0);
    EXPECT_LT(sc.maxVelocityError(r), 0.05);
    EXPECT_LT((r.bias.gyro - sc.o.bias.gyro).norm(), 2e-3);
    EXPECT_LT(sc.scaleError(lin), 0.02);  // the linear stage alone is already within the brief
    EXPECT_LT(sc.gravityErrorDeg(lin), 1.0);
  }
}

TEST(ViInit, UsesTheTimeOffset) {
  // IMU clock 10 ms ahead: with the offset given, the result is as good as without one.
  Scenario sc(AnalyticTrajectory::medium(), 13, 0.25, 5, 0.010);
  const ViInitResult r = initializeVisualInertial(sc.kfs, sc.imu, sc.o.noise, sc.T_cm_i, 0.010);
  ASSERT_TRUE(r.success) << r.status;
  EXPECT_LT(sc.scaleError(r), 0.02);
  EXPECT_LT(sc.gravityErrorDeg(r), 1.0);
}

// estimateTimeOffset: the IMU clock ahead by 13.7 ms (off every grid point of the search) and the
// search started from 0 over +- 50 ms finds it from the rotations alone, with a biased noisy gyroscope;
// behind by 21.3 ms the same. A range of 0 leaves the starting offset.
TEST(ViInit, FindsTheTimeOffsetFromTheRotations) {
  for (double truth : {0.0137, -0.0213}) {
    Scenario sc(AnalyticTrajectory::medium(), 13, 0.25, 9, truth);
    double curvature = 0.0;
    const double est =
        estimateTimeOffset(sc.kfs, sc.imu, sc.o.noise, sc.T_cm_i, 0.0, 0.050, ImuBias(), 3, &curvature);
    std::printf("offset truth %.2f ms, estimate %.3f ms, cost curvature %.3g rad^2/s^2\n", 1e3 * truth, 1e3 * est,
                curvature);
    EXPECT_NEAR(est, truth, 0.3e-3);
    EXPECT_GT(curvature, 0.0);
    EXPECT_EQ(estimateTimeOffset(sc.kfs, sc.imu, sc.o.noise, sc.T_cm_i, 0.004, 0.0), 0.004);
  }
}

TEST(ViInit, StaticSequenceDoesNotInitialiseAndSaysWhy) {
  Scenario sc(AnalyticTrajectory::stationary(), 13, 0.25, 7);
  const ViInitResult r = initializeVisualInertial(sc.kfs, sc.imu, sc.o.noise, sc.T_cm_i);
  EXPECT_FALSE(r.success);
  EXPECT_NE(r.status.find("excitation"), std::string::npos) << r.status;
  EXPECT_NE(r.status.find("min_accel_excitation_m_s2"), std::string::npos) << r.status;
  EXPECT_LT(r.accel_excitation_m_s2, 0.05);
  std::printf("static: %s\n", r.status.c_str());
}

TEST(ViInit, ConstantVelocityDoesNotInitialise) {
  AnalyticTrajectory tr = AnalyticTrajectory::stationary();
  tr.pos[0].slope = 0.8;  // straight line at 0.8 m/s, turning slowly: scale and gravity are not separable
  tr.yaw.slope = 0.3;
  Scenario sc(tr, 13, 0.25, 8);
  const ViInitResult r = initializeVisualInertial(sc.kfs, sc.imu, sc.o.noise, sc.T_cm_i);
  EXPECT_FALSE(r.success);
  EXPECT_NE(r.status.find("excitation"), std::string::npos) << r.status;
}

TEST(ViInit, ConditioningThresholdIsEnforced) {
  Scenario sc(AnalyticTrajectory::medium(), 13, 0.25, 10);
  ViInitOptions opt;
  opt.min_relative_singular_value = 0.5;  // the medium scenario measures ~0.05
  const ViInitResult r = initializeVisualInertial(sc.kfs, sc.imu, sc.o.noise, sc.T_cm_i, 0.0, opt);
  EXPECT_FALSE(r.success);
  EXPECT_NE(r.status.find("min_relative_singular_value"), std::string::npos) << r.status;
  EXPECT_GT(r.relative_singular_value, 0.0);
}

TEST(ViInit, RejectsInconsistentGravityMagnitude) {
  // An accelerometer bias of 2 m/s^2 along the body z axis (uncalibrated, not in the model) makes the
  // unconstrained gravity estimate far from 9.81: refuse rather than produce a wrong scale.
  Scenario sc(AnalyticTrajectory::medium(), 13, 0.25, 11);
  ImuBuffer biased;
  for (ImuSample s : sc.imu.samples()) {
    s.accel_m_s2.z() += 2.0;
    biased.add(s);
  }
  const ViInitResult r = initializeVisualInertial(sc.kfs, biased, sc.o.noise, sc.T_cm_i);
  EXPECT_FALSE(r.success);
  EXPECT_NE(r.status.find("max_gravity_norm_error"), std::string::npos) << r.status;
}

TEST(ViInit, WaitsForEnoughKeyframes) {
  Scenario sc(AnalyticTrajectory::medium(), 4, 0.25, 9);
  const ViInitResult r = initializeVisualInertial(sc.kfs, sc.imu, sc.o.noise, sc.T_cm_i);
  EXPECT_FALSE(r.success);
  EXPECT_NE(r.status.find("min_keyframes"), std::string::npos) << r.status;
}

// With min_interval_s the solve uses keyframes at least that far apart (picked back from the newest)
// and every keyframe still gets a velocity, the others' propagated through the IMU.
TEST(ViInit, SpacedSubsetGivesEveryKeyframeAVelocity) {
  Scenario sc(AnalyticTrajectory::medium(), 31, 0.1, 12);  // 3 s at 10 Hz
  ViInitOptions opt;
  opt.min_interval_s = 0.3;
  const ViInitResult r = initializeVisualInertial(sc.kfs, sc.imu, sc.o.noise, sc.T_cm_i, 0.0, opt);
  ASSERT_TRUE(r.success) << r.status;
  ASSERT_EQ(r.velocities_wm.size(), sc.kfs.size());
  EXPECT_LT(sc.scaleError(r), 0.02);
  EXPECT_LT(sc.gravityErrorDeg(r), 1.0);
  EXPECT_LT(sc.maxVelocityError(r), 0.05);
  EXPECT_NEAR(r.duration_s, 3.0, 1e-6);
  ViInitOptions few = opt;
  few.min_interval_s = 1.2;  // 3 picked < min_subset_keyframes 4
  const ViInitResult w = initializeVisualInertial(sc.kfs, sc.imu, sc.o.noise, sc.T_cm_i, 0.0, few);
  EXPECT_FALSE(w.success);
  EXPECT_NE(w.status.find("min_interval_s"), std::string::npos) << w.status;
}

// Keyframe position noise enters the linear system's accelerations divided by dt^2, in the regressor:
// over consecutive 0.1 s intervals it biases the scale low (errors in variables), over 0.3 s it does
// much less (the figure behind imu.init_min_interval_s in rs_vio.json, docs/vio.md). The IMU factors'
// whitened energy at the solution shows the misfit.
TEST(ViInit, NoisyPosesBiasTheScaleLowOverShortIntervalsOnly) {
  double low_all = 0.0, low_spaced = 0.0;
  for (uint64_t seed : {21u, 22u, 23u}) {
    Scenario sc(AnalyticTrajectory::medium(), 31, 0.1, seed);
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> n(0.0, 0.005 / sc.T_wm_wf.scale());  // 5 mm per axis, in W_f units
    for (ViInitKeyframe& k : sc.kfs) {
      SE3d T_wf_cf = k.T_cf_wf.inverse();
      T_wf_cf.translation() += Vec3(n(rng), n(rng), n(rng));
      k.T_cf_wf = T_wf_cf.inverse();
    }
    const ViInitResult all = initializeVisualInertial(sc.kfs, sc.imu, sc.o.noise, sc.T_cm_i);
    ViInitOptions opt;
    opt.min_interval_s = 0.3;
    const ViInitResult spaced = initializeVisualInertial(sc.kfs, sc.imu, sc.o.noise, sc.T_cm_i, 0.0, opt);
    ASSERT_TRUE(all.success) << all.status;
    ASSERT_TRUE(spaced.success) << spaced.status;
    const double ra = all.T_wm_wf.scale() / sc.T_wm_wf.scale(), rs = spaced.T_wm_wf.scale() / sc.T_wm_wf.scale();
    std::printf("seed %d, 5 mm pose noise: scale ratio %.3f over 0.1 s intervals (IMU energy %.0f per factor), %.3f "
                "over >= 0.3 s (%.0f)\n",
                static_cast<int>(seed), ra, all.imu_chi2_mean, rs, spaced.imu_chi2_mean);
    low_all += (1.0 - ra) / 3.0;
    low_spaced += std::abs(1.0 - rs) / 3.0;
    EXPECT_GT(all.imu_chi2_mean, 15.0 * 10);  // far above a consistent factor's ~15
  }
  // Measured: ratios 0.21-0.31 over 0.1 s (energy 6e4-8e4 per factor), 0.93-0.99 over >= 0.3 s (6e3-2e4).
  EXPECT_GT(low_all, 0.3) << "consecutive intervals: the scale should come out low";
  EXPECT_LT(low_spaced, 0.25 * low_all);
  EXPECT_LT(low_spaced, 0.08);
}

}  // namespace
}  // namespace rsvio
