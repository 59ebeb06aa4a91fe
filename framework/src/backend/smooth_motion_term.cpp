// Smooth-motion prior on the rolling-shutter twists (contract in rsvio/backend/smooth_motion_term.h).
#include "rsvio/backend/smooth_motion_term.h"

#include <algorithm>
#include <cmath>

#include "rsvio/core/time.h"

namespace rsvio {

bool SmoothMotionTerm::evaluate(const Keyframe& k, Eval* e) const {
  if (!k.motion_term) return false;
  const Keyframe* a = k.motion_prev ? k.motion_prev : &k;
  const Keyframe* b = k.motion_next ? k.motion_next : &k;
  if (a == b) return false;
  const double D = nsToS(b->t_ns - a->t_ns);
  if (!(D > 1e-6)) return false;
  const Vec6 u = (b->state.T_c_w * a->state.T_c_w.inverse()).log();
  e->a = a;
  e->b = b;
  e->r = k.state.twist - u / D;
  e->d_r_d_xi = Mat6::Identity();
  e->d_r_d_Tb = -SE3d::leftJacobianInverse(u) / D;
  e->d_r_d_Ta = SE3d::rightJacobianInverse(u) / D;
  const double f = D > o_.gap_ref_s ? (o_.gap_ref_s / D) * (o_.gap_ref_s / D) : 1.0;
  e->W = o_.information * (f * k.motion_weight);
  e->W.bottomRightCorner<3, 3>() *= k.motion_weight_rot;
  return true;
}

namespace {

// Adds J_i^T W J_j and -J_i^T W r over the involved blocks; `offsets` gives each keyframe's row in H.
void accumulate(const SmoothMotionTerm::Eval& e, const Keyframe& k,
                const std::vector<std::pair<const Keyframe*, int>>& offsets, Eigen::MatrixXd& H, Eigen::VectorXd& b) {
  // Jacobian columns per keyframe: k's twist, a's pose, b's pose (a or b may be k).
  struct Col {
    const Keyframe* kf;
    int col;  // offset inside the keyframe block
    Mat6 J;
  };
  const Col cols[3] = {{&k, StateLayout::kTwist, e.d_r_d_xi}, {e.a, StateLayout::kPose, e.d_r_d_Ta},
                       {e.b, StateLayout::kPose, e.d_r_d_Tb}};
  auto offsetOf = [&](const Keyframe* kf) {
    for (const auto& [p, o] : offsets)
      if (p == kf) return o;
    return -1;
  };
  const Vec6 Wr = e.W * e.r;
  for (const Col& ci : cols) {
    const int oi = offsetOf(ci.kf);
    if (oi < 0) continue;
    b.segment<6>(oi + ci.col) -= ci.J.transpose() * Wr;
    const Mat6 JtW = ci.J.transpose() * e.W;
    for (const Col& cj : cols) {
      const int oj = offsetOf(cj.kf);
      if (oj < 0) continue;
      H.block<6, 6>(oi + ci.col, oj + cj.col) += JtW * cj.J;
    }
  }
}

}  // namespace

double SmoothMotionTerm::linearize(const KeyframeList& window, const StateLayout& layout, Eigen::MatrixXd& H,
                                   Eigen::VectorXd& b) const {
  if (!layout.rolling) return 0.0;
  const int kd = layout.kfDim();
  std::vector<std::pair<const Keyframe*, int>> offsets;
  offsets.reserve(window.size());
  for (const auto& kf : window) offsets.emplace_back(kf.get(), kf->index * kd);
  double energy = 0.0;
  Eval e;
  for (const auto& kf : window) {
    if (!evaluate(*kf, &e)) continue;
    accumulate(e, *kf, offsets, H, b);
    energy += e.r.dot(e.W * e.r);
  }
  return energy;
}

double SmoothMotionTerm::linearizeOne(const Keyframe& k, const StateLayout& layout, std::vector<Keyframe*>* kfs,
                                      Eigen::MatrixXd* H, Eigen::VectorXd* b) const {
  kfs->clear();
  Eval e;
  if (!layout.rolling || !evaluate(k, &e)) {
    H->resize(0, 0);
    b->resize(0);
    return 0.0;
  }
  for (const Keyframe* p : {e.a, &k, e.b})
    if (std::find(kfs->begin(), kfs->end(), p) == kfs->end()) kfs->push_back(const_cast<Keyframe*>(p));
  std::sort(kfs->begin(), kfs->end(), [](const Keyframe* x, const Keyframe* y) { return x->index < y->index; });
  const int kd = layout.kfDim();
  std::vector<std::pair<const Keyframe*, int>> offsets;
  for (size_t i = 0; i < kfs->size(); ++i) offsets.emplace_back((*kfs)[i], static_cast<int>(i) * kd);
  H->setZero(static_cast<Eigen::Index>(kfs->size()) * kd, static_cast<Eigen::Index>(kfs->size()) * kd);
  b->setZero(static_cast<Eigen::Index>(kfs->size()) * kd);
  accumulate(e, k, offsets, *H, *b);
  return e.r.dot(e.W * e.r);
}

}  // namespace rsvio
