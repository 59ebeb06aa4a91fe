#include "rsvio/imu/imu_factor.h"

#include <Eigen/Cholesky>

namespace rsvio {

ImuFactor::ImuFactor(ImuPreintegration pre, const Vec3& gravity_w) : pre_(std::move(pre)), g_(gravity_w) {}

Vec15 ImuFactor::residual(const ImuState& si, const ImuState& sj, double time_offset_s, ImuFactorJacobians* J) const {
  const double dt = pre_.dt();
  const ImuPreintegration::Delta d = pre_.corrected(si.bias, time_offset_s);
  const SO3d Ri_inv = si.R_w_i.inverse();
  const Vec3 dv_world = sj.v_w - si.v_w - g_ * dt;
  const Vec3 dp_world = sj.p_w_i - si.p_w_i - si.v_w * dt - 0.5 * g_ * dt * dt;
  const Vec3 dv_i = Ri_inv * dv_world;  // R_i^T (v_j - v_i - g dt)
  const Vec3 dp_i = Ri_inv * dp_world;

  Vec15 r;
  const Vec3 r_R = (d.R.inverse() * Ri_inv * sj.R_w_i).log();
  r.segment<3>(kResRot) = r_R;
  r.segment<3>(kResVel) = dv_i - d.v;
  r.segment<3>(kResPos) = dp_i - d.p;
  r.segment<3>(kResBg) = sj.bias.gyro - si.bias.gyro;
  r.segment<3>(kResBa) = sj.bias.accel - si.bias.accel;
  if (!J) return r;

  // Derivations: docs/imu.md, "IMU factor Jacobians". log(exp(a) exp(r)) = r + Jl^-1(r) a and
  // log(exp(r) exp(a)) = r + Jr^-1(r) a to first order.
  const Mat3 Jl_inv = SO3d::leftJacobianInverse(r_R);
  const Mat3 Jr_inv = SO3d::rightJacobianInverse(r_R);
  const Mat3 Jr_phi = SO3d::rightJacobian(d.phi);
  const Mat3 Ri_t = Ri_inv.matrix();
  const Mat3 dR_t = d.R.inverse().matrix();

  Mat15& Ji = J->d_res_d_state_i;
  Mat15& Jj = J->d_res_d_state_j;
  Ji.setZero();
  Jj.setZero();
  // r_R
  Ji.block<3, 3>(kResRot, kStateRot) = -Jl_inv * dR_t;
  Ji.block<3, 3>(kResRot, kStateBg) = -Jl_inv * Jr_phi * pre_.d_R_d_bg();
  Jj.block<3, 3>(kResRot, kStateRot) = Jr_inv;
  // r_v
  Ji.block<3, 3>(kResVel, kStateRot) = SO3d::hat(dv_i);
  Ji.block<3, 3>(kResVel, kStateVel) = -Ri_t;
  Ji.block<3, 3>(kResVel, kStateBg) = -pre_.d_v_d_bg();
  Ji.block<3, 3>(kResVel, kStateBa) = -pre_.d_v_d_ba();
  Jj.block<3, 3>(kResVel, kStateVel) = Ri_t;
  // r_p (p <- p + R dp, so d p_j / d dp_j = R_j)
  Ji.block<3, 3>(kResPos, kStateRot) = SO3d::hat(dp_i);
  Ji.block<3, 3>(kResPos, kStatePos) = -Mat3::Identity();
  Ji.block<3, 3>(kResPos, kStateVel) = -Ri_t * dt;
  Ji.block<3, 3>(kResPos, kStateBg) = -pre_.d_p_d_bg();
  Ji.block<3, 3>(kResPos, kStateBa) = -pre_.d_p_d_ba();
  Jj.block<3, 3>(kResPos, kStatePos) = Ri_t * sj.R_w_i.matrix();
  // bias random walk
  Ji.block<3, 3>(kResBg, kStateBg) = -Mat3::Identity();
  Ji.block<3, 3>(kResBa, kStateBa) = -Mat3::Identity();
  Jj.block<3, 3>(kResBg, kStateBg) = Mat3::Identity();
  Jj.block<3, 3>(kResBa, kStateBa) = Mat3::Identity();
  // time offset: the corrected measurement moves along its first-order offset model.
  J->d_res_d_offset.setZero();
  J->d_res_d_offset.segment<3>(kResRot) = -Jl_inv * Jr_phi * pre_.d_R_d_offset();
  J->d_res_d_offset.segment<3>(kResVel) = -pre_.d_v_d_offset();
  J->d_res_d_offset.segment<3>(kResPos) = -pre_.d_p_d_offset();
  return r;
}

ImuState predictState(const ImuState& s, const ImuPreintegration& pre, const Vec3& g) {
  const double dt = pre.dt();
  const ImuPreintegration::Delta d = pre.corrected(s.bias);
  ImuState r = s;
  r.R_w_i = s.R_w_i * d.R;                                                  // eq. 13
  r.p_w_i = s.p_w_i + s.v_w * dt + 0.5 * g * dt * dt + s.R_w_i * d.p;       // eq. 14
  r.v_w = s.v_w + g * dt + s.R_w_i * d.v;                                   // eq. 15
  return r;
}

Mat15 ImuFactor::information() const {
  const Mat15 cov = pre_.fullCovariance();
  // Symmetric positive definite for any interval with at least one step and non-zero noise.
  return cov.ldlt().solve(Mat15::Identity());
}

Mat15 ImuFactor::sqrtInformation() const {
  const Mat15 info = information();
  const Mat15 sym = 0.5 * (info + info.transpose());
  return sym.llt().matrixU();
}

}  // namespace rsvio
