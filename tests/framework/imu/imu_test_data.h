// Synthetic IMU data with analytic truth for the IMU tests (the simulator is a separate component;
// these tests must not depend on it).
//
// Trajectory: body (= IMU) position p(t) = c + A .* sin(f .* t + phase) per axis, orientation
// R(t) = Rz(yaw) Ry(pitch) Rx(roll) with each angle a0 + B sin(h t + psi). Derivatives are analytic:
//   specific force  a_meas = R^T (p'' - g) + b_a,   g = (0, 0, -9.81)
//   gyroscope       w_meas = w_body + b_g,  w_body from the ZYX angle rates:
//                   w_body = Rx^T Ry^T (0,0,yaw') + Rx^T (0,pitch',0) + (roll',0,0)
// Noise per sample: sigma_d = density * sqrt(rate) (white), optional bias random walk with
// sigma = density_rw / sqrt(rate) per sample.
#pragma once
#include <cmath>
#include <random>
#include <vector>

#include "rsvio/core/types.h"
#include "rsvio/imu/imu_frames.h"
#include "rsvio/imu/imu_types.h"
#include "rsvio/lie/rxso3.h"
#include "rsvio/lie/se3.h"
#include "rsvio/lie/so3.h"

namespace rsvio {
namespace test {

struct Sinusoid {
  // value = offset + amp sin(freq t + phase) + slope t
  double offset = 0.0, amplitude = 0.0, freq = 0.0, phase = 0.0, slope = 0.0;
  double value(double t) const { return offset + amplitude * std::sin(freq * t + phase) + slope * t; }
  double rate(double t) const { return amplitude * freq * std::cos(freq * t + phase) + slope; }
  double accel(double t) const { return -amplitude * freq * freq * std::sin(freq * t + phase); }
};

struct AnalyticTrajectory {
  Sinusoid pos[3];
  Sinusoid roll, pitch, yaw;

  Vec3 position(double t) const { return Vec3(pos[0].value(t), pos[1].value(t), pos[2].value(t)); }
  Vec3 velocity(double t) const { return Vec3(pos[0].rate(t), pos[1].rate(t), pos[2].rate(t)); }
  Vec3 acceleration(double t) const { return Vec3(pos[0].accel(t), pos[1].accel(t), pos[2].accel(t)); }
  SO3d rotation(double t) const {
    return SO3d::rotZ(yaw.value(t)) * SO3d::rotY(pitch.value(t)) * SO3d::rotX(roll.value(t));
  }
  Vec3 angularVelocityBody(double t) const {
    const Mat3 Rx = SO3d::rotX(roll.value(t)).matrix();
    const Mat3 Ry = SO3d::rotY(pitch.value(t)).matrix();
    return Rx.transpose() * Ry.transpose() * Vec3(0, 0, yaw.rate(t)) + Rx.transpose() * Vec3(0, pitch.rate(t), 0) +
           Vec3(roll.rate(t), 0, 0);
  }
  Vec3 specificForce(double t) const { return rotation(t).inverse() * Vec3(acceleration(t) - gravityWorld()); }

  ImuState state(double t, const ImuBias& bias = {}) const {
    ImuState s;
    s.R_w_i = rotation(t);
    s.p_w_i = position(t);
    s.v_w = velocity(t);
    s.bias = bias;
    return s;
  }

  // "Medium" motion: ~1 m and ~0.5 rad amplitudes, accelerations ~1-3 m/s^2, rates up to ~1 rad/s.
  static AnalyticTrajectory medium() {
    AnalyticTrajectory tr;
    tr.pos[0] = {0.3, 1.0, 1.3, 0.2};
    tr.pos[1] = {-0.5, 0.8, 1.7, 1.1};
    tr.pos[2] = {1.2, 0.4, 2.1, 0.4};
    tr.roll = {0.1, 0.3, 1.1, 0.3};
    tr.pitch = {-0.05, 0.25, 1.4, 1.0};
    tr.yaw = {0.4, 0.6, 0.9, 0.2};
    return tr;
  }
  // Fixed pose (a level-ish IMU at rest).
  static AnalyticTrajectory stationary() {
    AnalyticTrajectory tr;
    tr.pos[0].offset = 0.2;
    tr.pos[1].offset = -0.1;
    tr.pos[2].offset = 1.0;
    tr.roll.offset = 0.05;
    tr.pitch.offset = -0.03;
    tr.yaw.offset = 0.7;
    return tr;
  }
};

struct ImuSimOptions {
  double rate_hz = 200.0;
  ImuNoise noise;            // densities (used only when add_noise)
  ImuBias bias;              // initial bias
  bool add_noise = false;
  bool bias_random_walk = false;
  int64_t t0_ns = 0;         // first sample time; samples at t0 + k / rate
};

// IMU samples over [t_start_s, t_end_s] (inclusive of the sample grid within), truth from `tr`.
inline std::vector<ImuSample> simulateImu(const AnalyticTrajectory& tr, double t_start_s, double t_end_s,
                                          const ImuSimOptions& o, std::mt19937_64* rng = nullptr,
                                          std::vector<ImuBias>* true_bias = nullptr) {
  std::normal_distribution<double> n01(0.0, 1.0);
  auto gauss3 = [&]() { return Vec3(n01(*rng), n01(*rng), n01(*rng)); };
  const double dt = 1.0 / o.rate_hz;
  const double sg = o.noise.gyro_noise_density / std::sqrt(dt);
  const double sa = o.noise.accel_noise_density / std::sqrt(dt);
  const double swg = o.noise.gyro_random_walk * std::sqrt(dt);
  const double swa = o.noise.accel_random_walk * std::sqrt(dt);
  ImuBias b = o.bias;
  std::vector<ImuSample> out;
  const int64_t k0 = static_cast<int64_t>(std::ceil(t_start_s * o.rate_hz - 1e-9));
  const int64_t k1 = static_cast<int64_t>(std::floor(t_end_s * o.rate_hz + 1e-9));
  for (int64_t k = k0; k <= k1; ++k) {
    const double t = static_cast<double>(k) * dt;
    ImuSample s;
    s.t_ns = o.t0_ns + static_cast<int64_t>(std::llround(t * 1e9));
    s.gyro_rad_s = tr.angularVelocityBody(t) + b.gyro;
    s.accel_m_s2 = tr.specificForce(t) + b.accel;
    if (o.add_noise) {
      s.gyro_rad_s += sg * gauss3();
      s.accel_m_s2 += sa * gauss3();
    }
    if (true_bias) true_bias->push_back(b);
    if (o.bias_random_walk) {
      b.gyro += swg * gauss3();
      b.accel += swa * gauss3();
    }
    out.push_back(s);
  }
  return out;
}

// A non-identity IMU-to-camera extrinsic T_Cm_I (a small rotation and a few cm, like the simulator's):
// the camera looks forward (z) along the body x axis.
inline SE3d defaultCameraFromImu() {
  const SO3d R_i_c = SO3d(Mat3((Mat3() << 0, 0, 1, -1, 0, 0, 0, -1, 0).finished())) * SO3d::exp(Vec3(0.02, -0.03, 0.01));
  const SE3d T_i_c(R_i_c, Vec3(0.05, -0.02, 0.03));
  return T_i_c.inverse();
}

// An arbitrary free-scale world: 1 W_f unit = 2.5 m, tilted and turned.
inline RxSO3d defaultMetricFromFree() { return RxSO3d(2.5, SO3d::exp(Vec3(0.3, -0.2, 0.8))); }

// The non-metric camera pose T_Cf_Wf at time t of the analytic IMU trajectory.
inline SE3d cameraPoseAt(const AnalyticTrajectory& tr, double t, const SE3d& T_cm_i, const RxSO3d& T_wm_wf) {
  return cameraPoseFromImu(SE3d(tr.rotation(t), tr.position(t)), T_wm_wf, T_cm_i);
}

inline int64_t secToNs(double t) { return static_cast<int64_t>(std::llround(t * 1e9)); }

}  // namespace test
}  // namespace rsvio
