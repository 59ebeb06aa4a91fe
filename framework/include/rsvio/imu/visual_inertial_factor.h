// The IMU factor seen from the photometric bundle adjustment: residuals of eqs. 16-19 with the metric
// IMU poses computed from the optimised non-metric camera poses (paper Fig. 3, imu_frames.h).
//
// Contract
// - Variables per keyframe: T_Cf_Wf (LEFT perturbation (upsilon; omega), the optimiser's), the IMU
//   velocity v in W_m and the biases (additive), ordered (v, b_g, b_a) in d_res_d_vel_bias.
// - Shared variables: T_Wm_Wf (RxSO3d, LEFT perturbation (omega; sigma), sigma = log scale) and the
//   camera-IMU time offset in seconds (t_imu = t_cam + offset). Calibrated T_Cm_I = T_C_B is fixed.
// - The residual equals ImuFactor::residual at the IMU states of imuPoseFromCamera(); its Jacobians are
//   the ImuFactor's (Forster's right perturbation) chained with ImuPoseJacobians:
//       d_res/d_T_cf_wf = d_res/d(d_phi, d_p) * d(d_phi, d_p)/d(upsilon, omega)
//   and d_res/d_T_wm_wf the sum of both keyframes' chains.
// - Gauge: rotating W_m about gravity (omega_z of T_Wm_Wf) together with every velocity leaves every
//   IMU residual unchanged (yaw is unobservable); the optimiser fixes it, e.g. by not updating omega_z.
#pragma once
#include <Eigen/Core>

#include "rsvio/imu/imu_factor.h"
#include "rsvio/imu/imu_frames.h"

namespace rsvio {

struct VisualInertialKeyframe {
  SE3d T_cf_wf;
  Vec3 v_wm = Vec3::Zero();
  ImuBias bias;
};

struct VisualInertialJacobians {
  Eigen::Matrix<double, 15, 6> d_res_d_T_cf_wf_i, d_res_d_T_cf_wf_j;
  Eigen::Matrix<double, 15, 9> d_res_d_vel_bias_i, d_res_d_vel_bias_j;
  Eigen::Matrix<double, 15, 4> d_res_d_T_wm_wf;
  Vec15 d_res_d_offset;
};

// The metric IMU state of a keyframe (paper eq. 9) from the optimiser's variables.
ImuState imuStateOf(const VisualInertialKeyframe& kf, const RxSO3d& T_wm_wf, const SE3d& T_cm_i,
                    ImuPoseJacobians* J = nullptr);

Vec15 visualInertialResidual(const ImuFactor& factor, const VisualInertialKeyframe& kf_i,
                             const VisualInertialKeyframe& kf_j, const RxSO3d& T_wm_wf, const SE3d& T_cm_i,
                             double time_offset_s, VisualInertialJacobians* J = nullptr);

}  // namespace rsvio
