// The IMU twist prior and twist energy of a keyframe (paper eqs. 22-33).
//
// Contract
// - Twists are per second, (translation; rotation), acting on the LEFT of the camera-from-world pose:
//   T_Cf_Wf(t) = exp(xi t) T_Cf_Wf (paper eq. 6; conventions.md). The paper measures t in image rows
//   and multiplies by the row time t_d (eq. 32); in rsvio time is in seconds, so t_d = 1.
// - Inputs: the gyroscope reading at the keyframe's mid-row time (IMU clock: t_cam + offset), the IMU
//   velocity v in W_m, the gyro bias, the keyframe's T_Cf_Wf, T_Wm_Wf = (s, R_g) and T_Cm_I.
//       v_I    = R_ic R_cw R_g^T v                          (eqs. 22-23, R_CmCf = I)
//       xi_I   = (v_I; w - b_g)                             (eq. 24, acts on the right of T_Wm_I)
//       xi_cam = -Adj(T_Cm_I) xi_I                          (eq. 25, metric, left of T_Cm_Wm)
//       prior  = (xi_cam_t / s; xi_cam_r)                   (eq. 32 with t_d = 1)
//   Residual of the twist energy (eq. 33): r = prior - xi, energy r^T W r with a diagonal W.
// - Jacobians of r: w.r.t. v and b_g (additive), T_Cf_Wf (LEFT (upsilon; omega); the translation
//   columns are zero, the prior depends on the rotation only), T_Wm_Wf (LEFT (omega; sigma)) and the
//   twist xi (-I). Derivations in docs/imu.md.
#pragma once
#include <Eigen/Core>

#include "rsvio/imu/imu_buffer.h"
#include "rsvio/imu/imu_types.h"
#include "rsvio/lie/rxso3.h"
#include "rsvio/lie/se3.h"

namespace rsvio {

struct TwistPriorJacobians {
  Eigen::Matrix<double, 6, 3> d_res_d_v = Eigen::Matrix<double, 6, 3>::Zero();
  Eigen::Matrix<double, 6, 3> d_res_d_bg = Eigen::Matrix<double, 6, 3>::Zero();
  Eigen::Matrix<double, 6, 6> d_res_d_T_cf_wf = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 4> d_res_d_T_wm_wf = Eigen::Matrix<double, 6, 4>::Zero();
  Eigen::Matrix<double, 6, 6> d_res_d_twist = -Eigen::Matrix<double, 6, 6>::Identity();
};

// Eq. 25's rotation: the camera's rotation rate from the gyroscope, -R_Cm_I (w - b_g) (rad/s, the
// rotation part of a twist left of T_Cf_Wf). It is also eq. 32's rotation, which needs no pose,
// velocity, scale or gravity, so it serves before the visual-inertial initialisation.
Vec3 imuTwistRotation(const Vec3& gyro_meas, const Vec3& bias_gyro, const SE3d& T_cm_i);

// Eq. 32: the IMU's prediction of the keyframe's camera twist in W_f units per second.
Vec6 imuTwistPrior(const Vec3& gyro_meas, const Vec3& v_wm, const Vec3& bias_gyro, const SE3d& T_cf_wf,
                   const RxSO3d& T_wm_wf, const SE3d& T_cm_i);

// The IMU's twist of a later frame (camera time t_cam_ns >= t_from_cam_ns): eq. 32 at that time, from
// a keyframe's metric IMU state `from` at t_from_cam_ns (biases from.bias): the gyroscope interpolated
// at t_cam_ns + time_offset_s less from.bias.gyro, from.v_w propagated to t_cam_ns with the
// preintegrated IMU (eq. 15), the rotation of the frame's T_cf_wf (its pose or a guess of it). What
// the frame tracker holds and the candidate tracer uses for a rolling-shutter frame of a
// visual-inertial run (system/inertial_state.h). False (xi untouched) when `buffer` does not cover
// [t_from, t] on the IMU clock.
bool imuFrameTwist(const ImuBuffer& buffer, const ImuNoise& noise, const ImuState& from, int64_t t_from_cam_ns,
                   int64_t t_cam_ns, double time_offset_s, const SE3d& T_cf_wf, const RxSO3d& T_wm_wf,
                   const SE3d& T_cm_i, Vec6* xi);

// Eq. 33's residual r = prior - twist, with Jacobians (J may be null).
Vec6 twistResidual(const Vec6& twist, const Vec3& gyro_meas, const Vec3& v_wm, const Vec3& bias_gyro,
                   const SE3d& T_cf_wf, const RxSO3d& T_wm_wf, const SE3d& T_cm_i, TwistPriorJacobians* J = nullptr);

}  // namespace rsvio
