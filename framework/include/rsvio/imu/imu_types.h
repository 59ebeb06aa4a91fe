// Types shared by rsvio's inertial code (preintegration, IMU factor, twist prior, initialisation).
//
// Contract
// - Body = IMU frame I. The metric world W_m has z up and gravity (0, 0, -kGravityNorm) (conventions.md).
// - IMU samples are on the IMU clock; camera times convert with t_imu = t_cam + time_offset (Kalibr's
//   sign, conventions.md). Durations inside the IMU code are double seconds (dt_s).
// - ImuState is the paper's eq. 9 state s_i = [R_i, p_i, v_i, b_i] in W_m. Its 15-dim tangent is
//   Forster's (2017) RIGHT perturbation, used inside the IMU factor only:
//       R <- R exp(d_phi),  p <- p + R d_p,  v <- v + d_v,  b_g <- b_g + d_bg,  b_a <- b_a + d_ba,
//   ordered (d_phi, d_p, d_v, d_bg, d_ba) = indices kStateRot, kStatePos, kStateVel, kStateBg, kStateBa.
//   The chained Jacobians w.r.t. the optimiser's variables use the project's LEFT perturbation
//   (rsvio/lie/lie.h); imu_frames.h converts at that edge. docs/imu.md derives both.
// - The 15-dim IMU residual is ordered (r_R, r_v, r_p, r_bg, r_ba) (paper eqs. 16-19).
#pragma once
#include <Eigen/Core>

#include "rsvio/core/types.h"
#include "rsvio/lie/so3.h"

namespace rsvio {

using Vec4 = Eigen::Matrix<double, 4, 1>;
using Vec9 = Eigen::Matrix<double, 9, 1>;
using Vec15 = Eigen::Matrix<double, 15, 1>;
using Mat9 = Eigen::Matrix<double, 9, 9>;
using Mat15 = Eigen::Matrix<double, 15, 15>;

constexpr double kGravityNorm = 9.81;  // m/s^2, conventions.md
inline Vec3 gravityWorld() { return Vec3(0.0, 0.0, -kGravityNorm); }

// Indices into the 15-dim state tangent (Forster's right perturbation, see above).
constexpr int kStateRot = 0;
constexpr int kStatePos = 3;
constexpr int kStateVel = 6;
constexpr int kStateBg = 9;
constexpr int kStateBa = 12;
constexpr int kStateDim = 15;

// Indices into the 15-dim IMU residual (paper eqs. 16-19).
constexpr int kResRot = 0;
constexpr int kResVel = 3;
constexpr int kResPos = 6;
constexpr int kResBg = 9;
constexpr int kResBa = 12;
constexpr int kResDim = 15;

struct ImuBias {
  Vec3 gyro = Vec3::Zero();   // rad/s, subtracted from the gyroscope reading
  Vec3 accel = Vec3::Zero();  // m/s^2, subtracted from the accelerometer reading
};

// Paper eq. 9: metric IMU pose T_Wm_I = (R_w_i, p_w_i), IMU velocity in W_m, biases.
struct ImuState {
  SO3d R_w_i;
  Vec3 p_w_i = Vec3::Zero();
  Vec3 v_w = Vec3::Zero();
  ImuBias bias;
};

// Applies Forster's right perturbation (ordering above) to a state.
inline ImuState boxPlus(const ImuState& x, const Vec15& d) {
  ImuState r = x;
  r.R_w_i = x.R_w_i * SO3d::exp(d.segment<3>(kStateRot));
  r.p_w_i = x.p_w_i + (x.R_w_i * Vec3(d.segment<3>(kStatePos)));
  r.v_w = x.v_w + d.segment<3>(kStateVel);
  r.bias.gyro = x.bias.gyro + d.segment<3>(kStateBg);
  r.bias.accel = x.bias.accel + d.segment<3>(kStateBa);
  return r;
}

}  // namespace rsvio
