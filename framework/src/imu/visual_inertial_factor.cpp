#include "rsvio/imu/visual_inertial_factor.h"

namespace rsvio {

ImuState imuStateOf(const VisualInertialKeyframe& kf, const RxSO3d& T_wm_wf, const SE3d& T_cm_i, ImuPoseJacobians* J) {
  ImuState s;
  setPose(&s, imuPoseFromCamera(kf.T_cf_wf, T_wm_wf, T_cm_i, J));
  s.v_w = kf.v_wm;
  s.bias = kf.bias;
  return s;
}

Vec15 visualInertialResidual(const ImuFactor& factor, const VisualInertialKeyframe& kf_i,
                             const VisualInertialKeyframe& kf_j, const RxSO3d& T_wm_wf, const SE3d& T_cm_i,
                             double time_offset_s, VisualInertialJacobians* J) {
  ImuPoseJacobians Jpi, Jpj;
  const ImuState si = imuStateOf(kf_i, T_wm_wf, T_cm_i, J ? &Jpi : nullptr);
  const ImuState sj = imuStateOf(kf_j, T_wm_wf, T_cm_i, J ? &Jpj : nullptr);
  ImuFactorJacobians Jf;
  const Vec15 r = factor.residual(si, sj, time_offset_s, J ? &Jf : nullptr);
  if (!J) return r;
  // The pose columns (d_phi, d_p) of the state tangent are contiguous: kStateRot = 0, kStatePos = 3.
  static_assert(kStatePos == kStateRot + 3, "pose block of the state tangent must be (d_phi, d_p)");
  const Eigen::Matrix<double, 15, 6> d_res_d_pose_i = Jf.d_res_d_state_i.middleCols<6>(kStateRot);
  const Eigen::Matrix<double, 15, 6> d_res_d_pose_j = Jf.d_res_d_state_j.middleCols<6>(kStateRot);
  J->d_res_d_T_cf_wf_i = d_res_d_pose_i * Jpi.d_pose_d_T_cf_wf;
  J->d_res_d_T_cf_wf_j = d_res_d_pose_j * Jpj.d_pose_d_T_cf_wf;
  J->d_res_d_T_wm_wf = d_res_d_pose_i * Jpi.d_pose_d_T_wm_wf + d_res_d_pose_j * Jpj.d_pose_d_T_wm_wf;
  // (v, b_g, b_a) are contiguous and additive in both conventions.
  static_assert(kStateBg == kStateVel + 3 && kStateBa == kStateBg + 3, "(v, bg, ba) must be contiguous");
  J->d_res_d_vel_bias_i = Jf.d_res_d_state_i.middleCols<9>(kStateVel);
  J->d_res_d_vel_bias_j = Jf.d_res_d_state_j.middleCols<9>(kStateVel);
  J->d_res_d_offset = Jf.d_res_d_offset;
  return r;
}

}  // namespace rsvio
