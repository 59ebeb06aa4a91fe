#include "rsvio/imu/twist_prior.h"

#include "rsvio/core/time.h"
#include "rsvio/imu/imu_factor.h"
#include "rsvio/imu/preintegration.h"

namespace rsvio {

Vec3 imuTwistRotation(const Vec3& gyro_meas, const Vec3& bias_gyro, const SE3d& T_cm_i) {
  return -(T_cm_i.so3() * (gyro_meas - bias_gyro));
}

Vec6 imuTwistPrior(const Vec3& gyro_meas, const Vec3& v_wm, const Vec3& bias_gyro, const SE3d& T_cf_wf,
                   const RxSO3d& T_wm_wf, const SE3d& T_cm_i) {
  // Eqs. 22-23: the velocity rotated into the IMU frame through the camera's rotation.
  const Vec3 v_i = T_cm_i.so3().inverse() * (T_cf_wf.so3() * (T_wm_wf.so3().inverse() * v_wm));
  Vec6 xi_imu;
  xi_imu << v_i, gyro_meas - bias_gyro;             // eq. 24
  const Vec6 xi_cam = -(T_cm_i.Adj() * xi_imu);     // eq. 25
  Vec6 prior;
  prior << xi_cam.head<3>() / T_wm_wf.scale(), xi_cam.tail<3>();  // eq. 32, t_d = 1 (per second)
  return prior;
}

bool imuFrameTwist(const ImuBuffer& buffer, const ImuNoise& noise, const ImuState& from, int64_t t_from_cam_ns,
                   int64_t t_cam_ns, double time_offset_s, const SE3d& T_cf_wf, const RxSO3d& T_wm_wf,
                   const SE3d& T_cm_i, Vec6* xi) {
  const int64_t off = sToNs(time_offset_s);
  if (t_cam_ns < t_from_cam_ns || !buffer.covers(t_from_cam_ns + off, t_cam_ns + off)) return false;
  Vec3 v_wm = from.v_w;
  if (t_cam_ns > t_from_cam_ns)
    v_wm = predictState(from, ImuPreintegration::fromBuffer(buffer, t_from_cam_ns, t_cam_ns, noise, from.bias,
                                                            time_offset_s))
               .v_w;
  *xi = imuTwistPrior(buffer.interpolate(t_cam_ns + off).gyro_rad_s, v_wm, from.bias.gyro, T_cf_wf, T_wm_wf, T_cm_i);
  return true;
}

Vec6 twistResidual(const Vec6& twist, const Vec3& gyro_meas, const Vec3& v_wm, const Vec3& bias_gyro,
                   const SE3d& T_cf_wf, const RxSO3d& T_wm_wf, const SE3d& T_cm_i, TwistPriorJacobians* J) {
  const Vec6 prior = imuTwistPrior(gyro_meas, v_wm, bias_gyro, T_cf_wf, T_wm_wf, T_cm_i);
  if (J) {
    const double s_inv = 1.0 / T_wm_wf.scale();
    const Mat3 R_ci = T_cm_i.rotationMatrix();
    const Mat3 R_cw_gt = (T_cf_wf.so3() * T_wm_wf.so3().inverse()).matrix();  // R_cw R_g^T
    const Vec3 u = R_cw_gt * v_wm;  // metric velocity in camera axes, = R_ci v_I
    // prior_t = -(u + [t_ci]x R_ci (w - b_g)) / s,  prior_r = -R_ci (w - b_g).
    J->d_res_d_v.setZero();
    J->d_res_d_v.topRows<3>() = -s_inv * R_cw_gt;
    J->d_res_d_bg.topRows<3>() = s_inv * SO3d::hat(T_cm_i.translation()) * R_ci;
    J->d_res_d_bg.bottomRows<3>() = R_ci;
    // exp(omega) R_cw: u -> u + omega x u, so d(-u/s)/d omega = [u]x / s.
    J->d_res_d_T_cf_wf.setZero();
    J->d_res_d_T_cf_wf.block<3, 3>(0, 3) = s_inv * SO3d::hat(u);
    // exp(omega) R_g: R_g^T v -> R_g^T (v - omega x v) = R_g^T (v + [v]x omega).
    J->d_res_d_T_wm_wf.setZero();
    J->d_res_d_T_wm_wf.block<3, 3>(0, 0) = -s_inv * R_cw_gt * SO3d::hat(v_wm);
    J->d_res_d_T_wm_wf.block<3, 1>(0, 3) = -prior.head<3>();  // s <- e^sigma s divides by e^sigma
    J->d_res_d_twist = -Mat6::Identity();
  }
  return prior - twist;
}

}  // namespace rsvio
