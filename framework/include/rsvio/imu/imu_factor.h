// The IMU factor between two consecutive keyframes i, j (paper eqs. 13-20; Forster et al. 2017 eq. 45).
//
// Contract
// - States are metric (W_m, gravity g = (0, 0, -9.81) by default); see imu_types.h for ImuState, the
//   residual order (r_R, r_v, r_p, r_bg, r_ba) and the state tangent (Forster's RIGHT perturbation).
// - Residuals, with the bias- and offset-corrected preintegration dR, dv, dp of preintegration.h
//   evaluated at b_i and the current time offset:
//       r_R  = log(dR^T R_i^T R_j)                                   (eq. 16 with eq. 13)
//       r_v  = R_i^T (v_j - v_i - g dt) - dv                        (eq. 17 with eq. 15)
//       r_p  = R_i^T (p_j - p_i - v_i dt - 1/2 g dt^2) - dp         (eq. 18 with eq. 14)
//       r_bg = b_g,j - b_g,i,   r_ba = b_a,j - b_a,i                 (eq. 19)
//   The energy is r^T W r (eq. 20) with W = information() = fullCovariance()^-1.
// - Jacobians: d_res_d_state_i/j are 15x15 w.r.t. the right-perturbed states; d_res_d_offset is the
//   derivative w.r.t. the camera-IMU time offset in seconds (t_imu = t_cam + offset). For the
//   optimiser's variables (camera poses, scale-gravity) see visual_inertial_factor.h.
#pragma once
#include "rsvio/imu/imu_types.h"
#include "rsvio/imu/preintegration.h"

namespace rsvio {

struct ImuFactorJacobians {
  Mat15 d_res_d_state_i = Mat15::Zero();
  Mat15 d_res_d_state_j = Mat15::Zero();
  Vec15 d_res_d_offset = Vec15::Zero();
};

class ImuFactor {
 public:
  ImuFactor() = default;
  explicit ImuFactor(ImuPreintegration pre, const Vec3& gravity_w = gravityWorld());

  // time_offset_s: the current estimate of t_imu - t_cam (its difference to the preintegration's
  // linearisation offset is applied to first order).
  Vec15 residual(const ImuState& si, const ImuState& sj, double time_offset_s, ImuFactorJacobians* J = nullptr) const;
  Vec15 residual(const ImuState& si, const ImuState& sj, ImuFactorJacobians* J = nullptr) const {
    return residual(si, sj, pre_.timeOffsetLin(), J);
  }

  Mat15 information() const;
  // Upper-triangular U with U^T U = information(), to whiten residuals (r_w = U r) and Jacobians.
  Mat15 sqrtInformation() const;

  const ImuPreintegration& preintegration() const { return pre_; }
  const Vec3& gravity() const { return g_; }

 private:
  ImuPreintegration pre_;
  Vec3 g_ = gravityWorld();
};

// The state at the end of a preintegrated interval from the state at its start (eqs. 13-15 with the
// bias correction of eq. 44 at s.bias): the prediction the residuals compare against.
ImuState predictState(const ImuState& s, const ImuPreintegration& pre, const Vec3& gravity_w = gravityWorld());

}  // namespace rsvio
