#include "rsvio/imu/preintegration.h"

#include <cmath>
#include <string>

#include "rsvio/core/error.h"
#include "rsvio/core/time.h"

namespace rsvio {

ImuPreintegration::ImuPreintegration(const ImuNoise& noise, const ImuBias& bias_lin, double time_offset_lin_s)
    : noise_(noise), bias_lin_(bias_lin), offset_lin_s_(time_offset_lin_s) {}

ImuPreintegration ImuPreintegration::fromBuffer(const ImuBuffer& buffer, int64_t t0_cam_ns, int64_t t1_cam_ns,
                                                const ImuNoise& noise, const ImuBias& bias_lin, double time_offset_s) {
  const int64_t off_ns = sToNs(time_offset_s);
  const int64_t t0 = t0_cam_ns + off_ns;
  const int64_t t1 = t1_cam_ns + off_ns;
  if (!buffer.covers(t0, t1))
    throw DataError("IMU samples do not cover the preintegration window [" + std::to_string(t0) + ", " +
                    std::to_string(t1) + "] ns (IMU clock)");
  ImuPreintegration pre(noise, bias_lin, time_offset_s);
  pre.integrateKnots(buffer.window(t0, t1));
  return pre;
}

void ImuPreintegration::integrateKnots(const std::vector<ImuSample>& knots) {
  if (knots.empty()) return;
  size_t i = 0;
  if (!started_) {
    first_ = last_ = knots[0];
    started_ = true;
    i = 1;
  }
  for (; i < knots.size(); ++i) integrateStep(last_, knots[i]);
}

void ImuPreintegration::integrateStep(const ImuSample& k0, const ImuSample& k1) {
  if (!started_) {
    first_ = k0;
    started_ = true;
  }
  if (k1.t_ns <= k0.t_ns)
    throw Error("IMU preintegration: step from " + std::to_string(k0.t_ns) + " to " + std::to_string(k1.t_ns) +
                " ns does not go forward in time");
  const double dt = nsToS(k1.t_ns - k0.t_ns);
  const double dt2 = dt * dt;
  // Midpoint rule: mean of the two knots, bias-corrected at the linearisation bias.
  const Vec3 w = 0.5 * (k0.gyro_rad_s + k1.gyro_rad_s) - bias_lin_.gyro;
  const Vec3 a = 0.5 * (k0.accel_m_s2 + k1.accel_m_s2) - bias_lin_.accel;

  const SO3d step_R = SO3d::exp(w * dt);
  const SO3d half_R = SO3d::exp(w * (0.5 * dt));
  const Mat3 R_mid = (dR_ * half_R).matrix();  // rotation at the middle of the step
  const Mat3 Jr_step = SO3d::rightJacobian(w * dt);
  const Mat3 Jr_half = SO3d::rightJacobian(w * (0.5 * dt));
  const Mat3 step_Rt = step_R.matrix().transpose();
  const Mat3 half_Rt = half_R.matrix().transpose();
  const Mat3 Ra_hat = R_mid * SO3d::hat(a);  // d(R_mid a)/d(right perturbation of R_mid) = -Ra_hat

  // Error-state transition (d_phi, d_v, d_p) and noise input matrices (docs/imu.md).
  Mat9 A = Mat9::Identity();
  A.block<3, 3>(0, 0) = step_Rt;
  A.block<3, 3>(3, 0) = -Ra_hat * half_Rt * dt;
  A.block<3, 3>(6, 0) = -0.5 * Ra_hat * half_Rt * dt2;
  A.block<3, 3>(6, 3) = Mat3::Identity() * dt;
  Eigen::Matrix<double, 9, 3> Bg, Ba;
  Bg.block<3, 3>(0, 0) = Jr_step * dt;
  Bg.block<3, 3>(3, 0) = -Ra_hat * Jr_half * (0.5 * dt) * dt;
  Bg.block<3, 3>(6, 0) = -0.5 * Ra_hat * Jr_half * (0.5 * dt) * dt2;
  Ba.setZero();
  Ba.block<3, 3>(3, 0) = R_mid * dt;
  Ba.block<3, 3>(6, 0) = 0.5 * R_mid * dt2;
  const double qg = noise_.gyro_noise_density * noise_.gyro_noise_density / dt;
  const double qa = noise_.accel_noise_density * noise_.accel_noise_density / dt;
  cov_ = A * cov_ * A.transpose() + qg * Bg * Bg.transpose() + qa * Ba * Ba.transpose();

  // Bias Jacobians: the bias enters like a constant negative noise on every step (Forster app. B).
  const Mat3 d_Rmid_d_bg = half_Rt * d_R_d_bg_ - Jr_half * (0.5 * dt);
  d_p_d_bg_ += d_v_d_bg_ * dt - 0.5 * Ra_hat * d_Rmid_d_bg * dt2;
  d_p_d_ba_ += d_v_d_ba_ * dt - 0.5 * R_mid * dt2;
  d_v_d_bg_ += -Ra_hat * d_Rmid_d_bg * dt;
  d_v_d_ba_ += -R_mid * dt;
  d_R_d_bg_ = step_Rt * d_R_d_bg_ - Jr_step * dt;

  // The state itself (eqs. 10-12 with the midpoint rule).
  const Vec3 acc_i = R_mid * a;
  dp_ += dv_ * dt + 0.5 * acc_i * dt2;
  dv_ += acc_i * dt;
  dR_ = dR_ * step_R;
  dt_ += dt;
  ++steps_;
  last_ = k1;
}

Mat15 ImuPreintegration::fullCovariance() const {
  Mat15 c = Mat15::Zero();
  c.block<9, 9>(0, 0) = cov_;
  c.block<3, 3>(kResBg, kResBg) = Mat3::Identity() * noise_.gyro_random_walk * noise_.gyro_random_walk * dt_;
  c.block<3, 3>(kResBa, kResBa) = Mat3::Identity() * noise_.accel_random_walk * noise_.accel_random_walk * dt_;
  return c;
}

Vec3 ImuPreintegration::d_R_d_offset() const {
  const Vec3 w_i = first_.gyro_rad_s - bias_lin_.gyro;
  const Vec3 w_j = last_.gyro_rad_s - bias_lin_.gyro;
  return w_j - dR_.inverse() * w_i;
}

Vec3 ImuPreintegration::d_v_d_offset() const {
  const Vec3 w_i = first_.gyro_rad_s - bias_lin_.gyro;
  const Vec3 a_i = first_.accel_m_s2 - bias_lin_.accel;
  const Vec3 a_j = last_.accel_m_s2 - bias_lin_.accel;
  return -w_i.cross(dv_) + dR_ * a_j - a_i;
}

Vec3 ImuPreintegration::d_p_d_offset() const {
  const Vec3 w_i = first_.gyro_rad_s - bias_lin_.gyro;
  const Vec3 a_i = first_.accel_m_s2 - bias_lin_.accel;
  return -w_i.cross(dp_) + dv_ - a_i * dt_;
}

ImuPreintegration::Delta ImuPreintegration::corrected(const ImuBias& bias, double time_offset_s) const {
  const Vec3 dbg = bias.gyro - bias_lin_.gyro;
  const Vec3 dba = bias.accel - bias_lin_.accel;
  const double doff = time_offset_s - offset_lin_s_;
  Delta d;
  d.phi = d_R_d_bg_ * dbg;
  d.v = dv_ + d_v_d_bg_ * dbg + d_v_d_ba_ * dba;
  d.p = dp_ + d_p_d_bg_ * dbg + d_p_d_ba_ * dba;
  if (doff != 0.0) {
    d.phi += d_R_d_offset() * doff;
    d.v += d_v_d_offset() * doff;
    d.p += d_p_d_offset() * doff;
  }
  d.R = dR_ * SO3d::exp(d.phi);
  return d;
}

}  // namespace rsvio
