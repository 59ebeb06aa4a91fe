#include "rsvio/imu/imu_frames.h"

namespace rsvio {

SE3d metricCameraPose(const SE3d& T_cf_wf, const RxSO3d& T_wm_wf) {
  // T_Cm_Cf T_Cf_Wf T_Wf_Wm: p_Wm -> R_g^T p / s -> R_cw R_g^T p / s + t_cw -> times s.
  return SE3d(T_cf_wf.so3() * T_wm_wf.so3().inverse(), T_wm_wf.scale() * T_cf_wf.translation());
}

SE3d imuPoseFromCamera(const SE3d& T_cf_wf, const RxSO3d& T_wm_wf, const SE3d& T_cm_i, ImuPoseJacobians* J) {
  const SE3d T_wm_cm = metricCameraPose(T_cf_wf, T_wm_wf).inverse();
  const SE3d T_wm_i = T_wm_cm * T_cm_i;
  if (J) {
    const double s = T_wm_wf.scale();
    const Mat3 R_ic = T_cm_i.so3().inverse().matrix();
    const Mat3 R_iw = T_wm_i.so3().inverse().matrix();
    J->d_pose_d_T_cf_wf.setZero();
    J->d_pose_d_T_cf_wf.block<3, 3>(0, 3) = -R_ic;
    J->d_pose_d_T_cf_wf.block<3, 3>(3, 0) = -s * R_ic;
    J->d_pose_d_T_cf_wf.block<3, 3>(3, 3) = R_ic * SO3d::hat(T_cm_i.translation());
    J->d_pose_d_T_wm_wf.setZero();
    J->d_pose_d_T_wm_wf.block<3, 3>(0, 0) = R_iw;
    J->d_pose_d_T_wm_wf.block<3, 3>(3, 0) = -R_iw * SO3d::hat(T_wm_i.translation());
    J->d_pose_d_T_wm_wf.block<3, 1>(3, 3) = R_iw * T_wm_cm.translation();
  }
  return T_wm_i;
}

SE3d cameraPoseFromImu(const SE3d& T_wm_i, const RxSO3d& T_wm_wf, const SE3d& T_cm_i) {
  const SE3d T_cm_wm = T_cm_i * T_wm_i.inverse();
  // T_Cf_Wf = T_Cf_Cm T_Cm_Wm T_Wm_Wf: p_Wf -> s R_g p -> R_cw_m s R_g p + t -> divided by s.
  return SE3d(T_cm_wm.so3() * T_wm_wf.so3(), T_cm_wm.translation() / T_wm_wf.scale());
}

SE3d cameraFromImu(const Eigen::Isometry3d& T_B_C) {
  const Eigen::Isometry3d T_C_B = T_B_C.inverse();
  return SE3d(SO3d::fitToSO3(T_C_B.linear()), Vec3(T_C_B.translation()));
}

}  // namespace rsvio
