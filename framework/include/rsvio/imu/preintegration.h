// IMU preintegration between two keyframe times (paper eqs. 10-12; Forster et al. 2017, sec. V-VI).
//
// Contract
// - Integrates bias-corrected gyroscope and accelerometer readings over [t_i, t_j] on the IMU clock into
//   the relative motion (dR, dv, dp) expressed in the IMU frame at t_i (no gravity, no initial velocity):
//       dR_ij = R_i^T R_j,   dv_ij = R_i^T (v_j - v_i - g dt_ij),
//       dp_ij = R_i^T (p_j - p_i - v_i dt_ij - 1/2 g dt_ij^2)          (paper eqs. 13-15 rearranged).
// - Integration rule: between consecutive knots (interpolated samples at both window ends, every stored
//   sample inside, see imu_buffer.h) the measurement is the mean of the two knots (midpoint rule), and
//   the accelerometer is rotated with the rotation at the middle of the step. This is second-order
//   accurate; the paper's eqs. 10-12 are its first-order (Euler) special case. The covariance and the
//   bias Jacobians below are exact derivatives of this discrete rule.
// - Covariance of the error (d_phi, d_v, d_p) with dR_noisy = dR_true exp(d_phi) (Forster's right
//   convention), from continuous noise densities: per step the discrete white noise has covariance
//   density^2 / dt (sigma_d = density / sqrt(dt)); fullCovariance() adds the bias random walk over the
//   interval, density_rw^2 * dt_ij, for the bias residual (paper eq. 19).
// - Bias update without re-integration (Forster eq. 44), extended to the time offset to first order:
//       dR(b, o) = dR * exp(J_R_bg db_g + phi_t do)
//       dv(b, o) = dv + J_v_bg db_g + J_v_ba db_a + J_v_t do,    dp likewise,
//   db = b - bias_lin, do = offset - offset_lin. The offset terms come from moving both window ends
//   (t_imu = t_cam + offset) by do with the bias-corrected measurements at the ends (docs/imu.md):
//       phi_t = w_j - dR^T w_i,  J_v_t = -[w_i]x dv + dR a_j - a_i,  J_p_t = -[w_i]x dp + dv - a_i dt_ij.
//   Re-preintegrate when |db| or |do| grows large (the first-order model degrades quadratically).
#pragma once
#include <cstdint>
#include <vector>

#include "rsvio/core/types.h"
#include "rsvio/imu/imu_buffer.h"
#include "rsvio/imu/imu_types.h"
#include "rsvio/lie/so3.h"

namespace rsvio {

class ImuPreintegration {
 public:
  // Bias- and offset-corrected preintegrated measurement (Forster eq. 44).
  struct Delta {
    SO3d R;
    Vec3 v = Vec3::Zero();
    Vec3 p = Vec3::Zero();
    Vec3 phi = Vec3::Zero();  // the correction's rotation vector J_R_bg db_g + phi_t do (for Jacobians)
  };

  ImuPreintegration() = default;
  ImuPreintegration(const ImuNoise& noise, const ImuBias& bias_lin, double time_offset_lin_s = 0.0);

  // Preintegrates camera times [t0_cam_ns, t1_cam_ns] from `buffer`, picking samples at
  // t_imu = t_cam + time_offset_s. Throws DataError when the buffer does not cover the window.
  static ImuPreintegration fromBuffer(const ImuBuffer& buffer, int64_t t0_cam_ns, int64_t t1_cam_ns,
                                      const ImuNoise& noise, const ImuBias& bias_lin, double time_offset_s = 0.0);

  // Integrates the knots of a window in order (ImuBuffer::window). The first call sets the start knot.
  void integrateKnots(const std::vector<ImuSample>& knots);
  // One step from knot k0 to knot k1 (k1.t_ns > k0.t_ns), midpoint rule.
  void integrateStep(const ImuSample& k0, const ImuSample& k1);

  double dt() const { return dt_; }
  const SO3d& deltaR() const { return dR_; }
  const Vec3& deltaV() const { return dv_; }
  const Vec3& deltaP() const { return dp_; }
  const Mat9& covariance() const { return cov_; }  // order (rot, vel, pos)
  Mat15 fullCovariance() const;                    // residual order (rot, vel, pos, bg, ba)
  const ImuBias& biasLin() const { return bias_lin_; }
  double timeOffsetLin() const { return offset_lin_s_; }
  const ImuNoise& noise() const { return noise_; }
  int64_t startTimeImu() const { return first_.t_ns; }
  int64_t endTimeImu() const { return last_.t_ns; }
  int numSteps() const { return steps_; }

  // First-order bias Jacobians (right perturbation for R).
  const Mat3& d_R_d_bg() const { return d_R_d_bg_; }
  const Mat3& d_v_d_bg() const { return d_v_d_bg_; }
  const Mat3& d_v_d_ba() const { return d_v_d_ba_; }
  const Mat3& d_p_d_bg() const { return d_p_d_bg_; }
  const Mat3& d_p_d_ba() const { return d_p_d_ba_; }
  // Derivatives w.r.t. the time offset at the linearisation point (see the contract).
  Vec3 d_R_d_offset() const;
  Vec3 d_v_d_offset() const;
  Vec3 d_p_d_offset() const;

  Delta corrected(const ImuBias& bias, double time_offset_s) const;
  Delta corrected(const ImuBias& bias) const { return corrected(bias, offset_lin_s_); }

 private:
  ImuNoise noise_;
  ImuBias bias_lin_;
  double offset_lin_s_ = 0.0;
  double dt_ = 0.0;
  int steps_ = 0;
  bool started_ = false;
  ImuSample first_, last_;  // raw end knots (for the offset derivatives)
  SO3d dR_;
  Vec3 dv_ = Vec3::Zero();
  Vec3 dp_ = Vec3::Zero();
  Mat9 cov_ = Mat9::Zero();
  Mat3 d_R_d_bg_ = Mat3::Zero();
  Mat3 d_v_d_bg_ = Mat3::Zero();
  Mat3 d_v_d_ba_ = Mat3::Zero();
  Mat3 d_p_d_bg_ = Mat3::Zero();
  Mat3 d_p_d_ba_ = Mat3::Zero();
};

}  // namespace rsvio
