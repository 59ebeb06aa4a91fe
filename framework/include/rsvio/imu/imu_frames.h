// The paper's coordinate systems (its Fig. 3): metric IMU poses from the optimised non-metric camera poses.
//
// Contract
// - T_Cf_Wf (SE3d): camera-from-world pose in the free-scale world W_f, the photometric BA's variable.
// - T_Wm_Wf (RxSO3d, paper eq. 2): scale s and rotation R_g (gravity alignment), no translation:
//   p_Wm = s R_g p_Wf. T_Cm_Cf = (s, I): the same scale, identity rotation.
// - T_Cm_I (SE3d): calibrated IMU-to-camera transform, T_C_B = CameraCalibration::T_B_C^-1.
// - Metric camera pose: T_Cm_Wm = T_Cm_Cf T_Cf_Wf T_Wf_Wm = (R_cw R_g^T, s t_cw)   (a rigid SE(3) pose)
//   Metric IMU pose:    T_Wm_I = T_Wm_Cm T_Cm_I,  i.e.
//       R_w_i = R_g R_cw^T R_ci,   p_w_i = R_g R_cw^T (t_ci - s t_cw)
//   with (R_ci, t_ci) = T_Cm_I and (R_cw, t_cw) = T_Cf_Wf. docs/imu.md derives these.
// - Jacobians (ImuPoseJacobians): rows are the IMU pose's perturbation inside the IMU factor, Forster's
//   RIGHT one (d_phi; d_p) with R_w_i <- R_w_i exp(d_phi), p_w_i <- p_w_i + R_w_i d_p (imu_types.h);
//   columns are the optimiser's LEFT perturbations: T_Cf_Wf <- exp(upsilon; omega) T_Cf_Wf and
//   T_Wm_Wf <- exp(omega; sigma) T_Wm_Wf (rsvio/lie/lie.h). In closed form:
//       d(d_phi, d_p)/d(upsilon, omega)_Cf_Wf = [ 0,        -R_ic         ]
//                                               [ -s R_ic,  R_ic [t_ci]x   ]
//       d(d_phi, d_p)/d(omega, sigma)_Wm_Wf   = [ R_iw,             0          ]
//                                               [ -R_iw [p_w_i]x,   R_iw p_w_c ]
//   where R_ic = R_ci^T, R_iw = R_w_i^T and p_w_c the camera centre in W_m.
// - The IMU velocity v (in W_m) is its own variable and does not depend on these transforms.
#pragma once
#include <Eigen/Core>

#include "rsvio/imu/imu_types.h"
#include "rsvio/lie/rxso3.h"
#include "rsvio/lie/se3.h"

namespace rsvio {

struct ImuPoseJacobians {
  Eigen::Matrix<double, 6, 6> d_pose_d_T_cf_wf = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 4> d_pose_d_T_wm_wf = Eigen::Matrix<double, 6, 4>::Zero();
};

// T_Cm_Wm from the non-metric camera pose and T_Wm_Wf.
SE3d metricCameraPose(const SE3d& T_cf_wf, const RxSO3d& T_wm_wf);
// T_Wm_I (paper Fig. 3), with optional Jacobians (see the contract).
SE3d imuPoseFromCamera(const SE3d& T_cf_wf, const RxSO3d& T_wm_wf, const SE3d& T_cm_i,
                       ImuPoseJacobians* J = nullptr);
// The inverse map: the non-metric camera pose T_Cf_Wf of a metric IMU pose T_Wm_I.
SE3d cameraPoseFromImu(const SE3d& T_wm_i, const RxSO3d& T_wm_wf, const SE3d& T_cm_i);

// T_Cm_I = T_C_B from a calibration's T_B_C (camera -> body).
SE3d cameraFromImu(const Eigen::Isometry3d& T_B_C);

// The IMU state part of a pose (rotation and position) as used by ImuState.
inline void setPose(ImuState* s, const SE3d& T_wm_i) {
  s->R_w_i = T_wm_i.so3();
  s->p_w_i = T_wm_i.translation();
}

}  // namespace rsvio
