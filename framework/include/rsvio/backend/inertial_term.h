// The inertial terms of the window optimisation (paper eq. 34: E = E_ph + alpha E_IMU + beta E_twist):
// IMU factors between consecutive keyframes (eqs. 13-20, visual_inertial_factor.h) and, with a rolling
// shutter, the twist energy of each keyframe (eqs. 22-33, twist_prior.h), as one WindowTerm.
//
// Contract
// - Variables (window.h, StateLayout): per keyframe the non-metric pose T_Cf_Wf (LEFT perturbation),
//   the twist (rolling), the IMU velocity in W_m and both biases (additive); globally T_Wm_Wf (LEFT
//   (omega; sigma)) and, when estimated, the camera-IMU time offset in seconds (t_imu = t_cam + offset).
//   The calibrated T_Cm_I = T_C_B is fixed.
// - IMU factor of keyframe j (Keyframe::imu_term, imu_prev = i, imu_factor preintegrated over
//   [t_i, t_j] on the camera clock shifted by the offset): residual visualInertialResidual(), weight
//   alpha * ImuFactor::information() (the preintegrated covariance with the bias random walk), energy
//   r^T W r. Jacobians are the factor's (visual_inertial_factor.h: Forster's right perturbation inside,
//   chained to the optimiser's left perturbations at its edge).
// - Twist energy of keyframe k (Keyframe::twist_energy, rolling only): r = twistResidual() = IMU twist
//   prior (eq. 32 from the gyroscope reading at t_k, v_k, b_g,k, R_k and T_Wm_Wf) - xi_k, weight
//   beta * diag((s / sigma_t)^2 x3, (1 / sigma_r)^2 x3): sigma_t [m/s] metric, so in W_f units it is
//   sigma_t / s; s is the current scale, held constant in the weight (not differentiated).
// - Before the visual-inertial initialisation (StateLayout::inertial false; on when
//   gyro_bias_sigma_before_init_rad_s > 0): each linked factor contributes its rotation residual only,
//   r_R = Log(dR_ij^T R_i^T R_j) (rows 0-2 of the factor's residual, bias and velocities at their
//   states, which are zero then), on the two keyframes' pose columns. It needs no scale or gravity:
//   relative rotations are the same in W_f and W_m. Weight imu_weight * (Cov_RR + (sigma_bg dt)^2 I)^-1,
//   Cov_RR the preintegrated rotation covariance, sigma_bg the option (the bias is not estimated yet).
//   It keeps the monocular start's world from rotating against the gyroscope (docs/vio.md).
// - Before the initialisation, rolling shutter (on when twist_gyro_sigma_before_init_rad_s > 0): each
//   keyframe with twist_energy contributes the rotation rows of its twist energy alone,
//   r = -R_Cm_I (w - b_g) - xi_rot (eq. 32's rotation: no pose, scale or gravity in it), on its twist
//   columns, weight twist_weight / sigma^2 I. It holds the twists' rotation to the gyroscope where the
//   smooth-motion prior's finite differences lag a changing rate (docs/vio.md).
// - Lifetime (system/ keeps it): a keyframe gets its IMU factor from the newest keyframe when it enters
//   the window. When a keyframe leaves, every term that involves it (its own factor and twist energy,
//   the factor of the keyframe whose imu_prev it is) is linearised at the current states into the
//   marginalisation prior (linearizeInvolving) and switched off, so each term is counted once.
#pragma once
#include <Eigen/Core>
#include <vector>

#include "rsvio/backend/bundle_adjustment.h"
#include "rsvio/imu/imu_factor.h"
#include "rsvio/imu/visual_inertial_factor.h"
#include "rsvio/lie/se3.h"

namespace rsvio {

// A keyframe's optimiser variables as the IMU factor reads them (pose T_Cf_Wf, v in W_m, both biases).
VisualInertialKeyframe visualInertialStateOf(const Keyframe& k);

struct InertialTermOptions {
  double imu_weight = 1.0;       // alpha of eq. 34
  double twist_weight = 1.0;     // beta of eq. 34 (rolling shutter, twist energy on)
  double twist_sigma_trans_m_s = 0.1;
  double twist_sigma_rot_rad_s = 0.02;
  // Before the initialisation (layout without the inertial blocks): the gyroscope's relative rotations
  // (see the contract); the unknown gyro bias enters their covariance with this sigma. <= 0: off.
  double gyro_bias_sigma_before_init_rad_s = 0.0;
  // Before the initialisation, rolling shutter: the twist energy's rotation rows (see the contract)
  // with this sigma. <= 0: off.
  double twist_gyro_sigma_before_init_rad_s = 0.0;
};

class InertialTerm : public WindowTerm {
 public:
  InertialTerm(const InertialTermOptions& o, const SE3d& T_cm_i, const GlobalStates* globals)
      : o_(o), T_cm_i_(T_cm_i), g_(globals) {}

  double linearize(const KeyframeList& window, const StateLayout& layout, Eigen::MatrixXd& H,
                   Eigen::VectorXd& b) const override;

  // The terms that involve kf (see the contract's lifetime), at the current states: the keyframes they
  // involve (window order) and H, b over their stateDim() blocks followed by the global block.
  // Returns their energy; no keyframes when there is none.
  double linearizeInvolving(const Keyframe& kf, const KeyframeList& window, const StateLayout& layout,
                            std::vector<Keyframe*>* kfs, Eigen::MatrixXd* H, Eigen::VectorXd* b) const;

  // The IMU factor residual of keyframe j (15, order r_R, r_v, r_p, r_bg, r_ba) and its whitened
  // energy r^T W r; false when j has no active factor. For the diagnostics and the divergence tests.
  bool imuResidual(const Keyframe& j, Vec15* r, double* energy) const;
  // The twist-energy residual of keyframe k (6) and its energy; false when k has none.
  bool twistResidual(const Keyframe& k, Vec6* r, double* energy) const;

  const InertialTermOptions& options() const { return o_; }

 private:
  InertialTermOptions o_;
  SE3d T_cm_i_;
  const GlobalStates* g_;
};

}  // namespace rsvio
