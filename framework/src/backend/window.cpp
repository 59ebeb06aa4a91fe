// Keyframe state arithmetic in the block layout (contract in rsvio/backend/window.h).
#include "rsvio/backend/window.h"

#include <cmath>

namespace rsvio {

Eigen::VectorXd stateDelta(const KeyframeState& x, const KeyframeState& lin, const StateLayout& layout) {
  Eigen::VectorXd d(layout.stateDim());
  d.segment<6>(StateLayout::kPose) = (x.T_c_w * lin.T_c_w.inverse()).log();
  d[StateLayout::kAffine] = x.affine.a - lin.affine.a;
  d[StateLayout::kAffine + 1] = x.affine.b - lin.affine.b;
  if (layout.rolling) d.segment<6>(StateLayout::kTwist) = x.twist - lin.twist;
  if (layout.inertial) {
    const int o = layout.kfDim();
    d.segment<3>(o + StateLayout::kVel) = x.v_wm - lin.v_wm;
    d.segment<3>(o + StateLayout::kBiasGyro) = x.bias_gyro - lin.bias_gyro;
    d.segment<3>(o + StateLayout::kBiasAccel) = x.bias_accel - lin.bias_accel;
  }
  return d;
}

void scaleDirection(const KeyframeState& x, const StateLayout& layout, Eigen::Ref<Eigen::VectorXd> kf_block) {
  kf_block.setZero();
  kf_block.segment<3>(StateLayout::kPose) = x.T_c_w.translation();
  if (layout.rolling) kf_block.segment<3>(StateLayout::kTwist) = x.twist.head<3>();
}

bool projectOffDirection(const Eigen::VectorXd& n, Eigen::MatrixXd& H, Eigen::VectorXd& b) {
  const double nn = n.squaredNorm();
  if (!(nn > 0.0)) return false;
  const Eigen::VectorXd u = n / std::sqrt(nn);
  const Eigen::VectorXd Hu = H * u;
  const double uHu = u.dot(Hu);
  // Written as H - u Hu^T - Hu u^T + uHu u u^T, coefficient by coefficient in this order.
  const Eigen::MatrixXd H_p = H - u * Hu.transpose() - Hu * u.transpose() + uHu * (u * u.transpose());
  H = H_p;
  b = b - u * u.dot(b);
  return true;
}

void applyStep(KeyframeState& x, const Eigen::Ref<const Eigen::VectorXd>& step, const StateLayout& layout) {
  x.T_c_w = SE3d::exp(step.segment<6>(StateLayout::kPose)) * x.T_c_w;
  x.affine.a += step[StateLayout::kAffine];
  x.affine.b += step[StateLayout::kAffine + 1];
  if (layout.rolling) x.twist += step.segment<6>(StateLayout::kTwist);
  if (layout.inertial && step.size() >= layout.stateDim()) {
    const int o = layout.kfDim();
    x.v_wm += step.segment<3>(o + StateLayout::kVel);
    x.bias_gyro += step.segment<3>(o + StateLayout::kBiasGyro);
    x.bias_accel += step.segment<3>(o + StateLayout::kBiasAccel);
  }
}

Eigen::VectorXd globalDelta(const GlobalState& x, const GlobalState& lin, const StateLayout& layout) {
  Eigen::VectorXd d(layout.globalDim());
  if (layout.inertial) {
    d.head<4>() = (x.T_wm_wf * lin.T_wm_wf.inverse()).log();
    if (layout.estimate_time_offset) d[StateLayout::kGlobalOffset] = x.time_offset_s - lin.time_offset_s;
  }
  if (layout.lineDelay()) d[layout.lineDelayIndex()] = x.line_delay_s - lin.line_delay_s;
  return d;
}

void applyGlobalStep(GlobalState& x, const Eigen::Ref<const Eigen::VectorXd>& step, const StateLayout& layout) {
  if (layout.inertial) {
    x.T_wm_wf = RxSO3d::exp(step.head<4>()) * x.T_wm_wf;
    if (layout.estimate_time_offset) x.time_offset_s += step[StateLayout::kGlobalOffset];
  }
  if (layout.lineDelay()) x.line_delay_s += step[layout.lineDelayIndex()];
}

Eigen::VectorXd gatherState(const Eigen::VectorXd& x_win, int k, int n, const StateLayout& layout) {
  Eigen::VectorXd s(layout.stateDim());
  s.head(layout.kfDim()) = x_win.segment(layout.photometricOffset(k), layout.kfDim());
  if (layout.inertial) s.tail(StateLayout::kImuDim) = x_win.segment(layout.imuOffset(k, n), StateLayout::kImuDim);
  return s;
}

}  // namespace rsvio
