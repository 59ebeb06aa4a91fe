// Keyframe state arithmetic in the block layout (contract in rsvio/backend/window.h).
#include "rsvio/backend/window.h"

namespace rsvio {

Eigen::VectorXd stateDelta(const KeyframeState& x, const KeyframeState& lin, const StateLayout& layout) {
  Eigen::VectorXd d(layout.kfDim());
  d.segment<6>(StateLayout::kPose) = (x.T_c_w * lin.T_c_w.inverse()).log();
  d[StateLayout::kAffine] = x.affine.a - lin.affine.a;
  d[StateLayout::kAffine + 1] = x.affine.b - lin.affine.b;
  if (layout.rolling) d.segment<6>(StateLayout::kTwist) = x.twist - lin.twist;
  return d;
}

void applyStep(KeyframeState& x, const Eigen::Ref<const Eigen::VectorXd>& step, const StateLayout& layout) {
  x.T_c_w = SE3d::exp(step.segment<6>(StateLayout::kPose)) * x.T_c_w;
  x.affine.a += step[StateLayout::kAffine];
  x.affine.b += step[StateLayout::kAffine + 1];
  if (layout.rolling) x.twist += step.segment<6>(StateLayout::kTwist);
}

}  // namespace rsvio
