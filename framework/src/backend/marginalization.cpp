// The marginalisation prior (contract in rsvio/backend/marginalization.h).
#include "rsvio/backend/marginalization.h"

#include <Eigen/Eigenvalues>
#include <algorithm>

#include "rsvio/core/error.h"

namespace rsvio {

int MarginalizationPrior::blockOf(const Keyframe* kf) const {
  for (size_t i = 0; i < keyframes_.size(); ++i)
    if (keyframes_[i] == kf) return static_cast<int>(i);
  return -1;
}

void MarginalizationPrior::addKeyframe(Keyframe* kf) {
  if (blockOf(kf) >= 0) return;
  const int d = layout_.kfDim();
  const Eigen::Index n = H_.rows();
  H_.conservativeResize(n + d, n + d);
  H_.rightCols(d).setZero();
  H_.bottomRows(d).setZero();
  b_.conservativeResize(n + d);
  b_.tail(d).setZero();
  keyframes_.push_back(kf);
  kf->in_prior = true;
  kf->lin = kf->state;  // first estimate, frozen from now on
}

Eigen::VectorXd MarginalizationPrior::delta() const {
  const int d = layout_.kfDim();
  Eigen::VectorXd x(static_cast<Eigen::Index>(keyframes_.size()) * d);
  for (size_t i = 0; i < keyframes_.size(); ++i)
    x.segment(static_cast<Eigen::Index>(i) * d, d) = stateDelta(keyframes_[i]->state, keyframes_[i]->lin, layout_);
  return x;
}

void MarginalizationPrior::addTerm(const std::vector<Keyframe*>& kfs, const Eigen::MatrixXd& H_t,
                                   const Eigen::VectorXd& b_t) {
  const int d = layout_.kfDim();
  if (H_t.rows() != static_cast<Eigen::Index>(kfs.size()) * d || H_t.cols() != H_t.rows() || b_t.size() != H_t.rows())
    throw Error("MarginalizationPrior::addTerm: term size does not match its keyframes");
  for (Keyframe* kf : kfs) addKeyframe(kf);
  std::vector<int> blk(kfs.size());
  for (size_t i = 0; i < kfs.size(); ++i) blk[i] = blockOf(kfs[i]);
  // b at the linearisation point: the term's gradient at x moved back along its own Hessian.
  Eigen::VectorXd dl(H_t.rows());
  for (size_t i = 0; i < kfs.size(); ++i)
    dl.segment(static_cast<Eigen::Index>(i) * d, d) = stateDelta(kfs[i]->state, kfs[i]->lin, layout_);
  const Eigen::VectorXd b_lin = b_t + H_t * dl;
  for (size_t i = 0; i < kfs.size(); ++i) {
    b_.segment(blk[i] * d, d) += b_lin.segment(static_cast<Eigen::Index>(i) * d, d);
    for (size_t j = 0; j < kfs.size(); ++j)
      H_.block(blk[i] * d, blk[j] * d, d, d) +=
          H_t.block(static_cast<Eigen::Index>(i) * d, static_cast<Eigen::Index>(j) * d, d, d);
  }
}

void MarginalizationPrior::addScaleFreeTerm(const std::vector<Keyframe*>& kfs, const Eigen::MatrixXd& H_t,
                                            const Eigen::VectorXd& b_t, bool project_scale) {
  const int d = layout_.kfDim();
  if (!project_scale || H_t.rows() != static_cast<Eigen::Index>(kfs.size()) * d) return addTerm(kfs, H_t, b_t);
  for (Keyframe* kf : kfs) addKeyframe(kf);  // freezes x_lin of keyframes new to the prior
  Eigen::VectorXd n = Eigen::VectorXd::Zero(H_t.rows());
  for (size_t i = 0; i < kfs.size(); ++i) {
    const Eigen::Index o = static_cast<Eigen::Index>(i) * d;
    n.segment<3>(o + StateLayout::kPose) = kfs[i]->lin.T_c_w.translation();
    if (layout_.rolling) n.segment<3>(o + StateLayout::kTwist) = kfs[i]->lin.twist.head<3>();
  }
  const double nn = n.squaredNorm();
  if (!(nn > 0.0)) return addTerm(kfs, H_t, b_t);
  const Eigen::VectorXd u = n / std::sqrt(nn);
  const Eigen::VectorXd Hu = H_t * u;
  const double uHu = u.dot(Hu);
  const Eigen::MatrixXd H_p = H_t - u * Hu.transpose() - Hu * u.transpose() + uHu * (u * u.transpose());
  const Eigen::VectorXd b_p = b_t - u * u.dot(b_t);
  addTerm(kfs, H_p, b_p);
}

void MarginalizationPrior::marginalizeKeyframe(Keyframe* kf) {
  const int k = blockOf(kf);
  if (k < 0) return;
  const int d = layout_.kfDim();
  const Eigen::Index n = H_.rows();
  // Permutation: keep = every other block, in order.
  std::vector<Eigen::Index> keep;
  for (Eigen::Index i = 0; i < n; ++i)
    if (i < k * d || i >= (k + 1) * d) keep.push_back(i);
  const Eigen::Index r = static_cast<Eigen::Index>(keep.size());
  Eigen::MatrixXd H_rr(r, r), H_rk(r, d);
  Eigen::VectorXd b_r(r);
  for (Eigen::Index i = 0; i < r; ++i) {
    b_r[i] = b_[keep[i]];
    H_rk.row(i) = H_.block(keep[i], k * d, 1, d);
    for (Eigen::Index j = 0; j < r; ++j) H_rr(i, j) = H_(keep[i], keep[j]);
  }
  Eigen::MatrixXd H_kk = H_.block(k * d, k * d, d, d);
  H_kk = 0.5 * (H_kk + H_kk.transpose()).eval();
  const Eigen::VectorXd b_k = b_.segment(k * d, d);
  // Pseudo-inverse: directions without information (zero rows of fixed dimensions) are conditioned on.
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(H_kk);
  const Eigen::VectorXd ev = es.eigenvalues();
  const double emax = std::max(ev.cwiseAbs().maxCoeff(), 0.0);
  Eigen::VectorXd inv(d);
  for (int i = 0; i < d; ++i) inv[i] = ev[i] > 1e-12 * emax && ev[i] > 0.0 ? 1.0 / ev[i] : 0.0;
  const Eigen::MatrixXd H_kk_pinv = es.eigenvectors() * inv.asDiagonal() * es.eigenvectors().transpose();
  Eigen::MatrixXd H_new = H_rr - H_rk * H_kk_pinv * H_rk.transpose();
  H_ = 0.5 * (H_new + H_new.transpose());
  b_ = b_r - H_rk * (H_kk_pinv * b_k);
  keyframes_.erase(keyframes_.begin() + k);
  kf->in_prior = false;
}

double MarginalizationPrior::energy() const {
  if (keyframes_.empty()) return 0.0;
  const Eigen::VectorXd dl = delta();
  return dl.dot(H_ * dl) - 2.0 * b_.dot(dl);
}

double MarginalizationPrior::addTo(Eigen::MatrixXd& H_win, Eigen::VectorXd& b_win) const {
  if (keyframes_.empty()) return 0.0;
  const int d = layout_.kfDim();
  const Eigen::VectorXd dl = delta();
  const Eigen::VectorXd b_cur = b_ - H_ * dl;
  for (size_t i = 0; i < keyframes_.size(); ++i) {
    const int wi = keyframes_[i]->index;
    b_win.segment(wi * d, d) += b_cur.segment(static_cast<Eigen::Index>(i) * d, d);
    for (size_t j = 0; j < keyframes_.size(); ++j)
      H_win.block(wi * d, keyframes_[j]->index * d, d, d) +=
          H_.block(static_cast<Eigen::Index>(i) * d, static_cast<Eigen::Index>(j) * d, d, d);
  }
  return dl.dot(H_ * dl) - 2.0 * b_.dot(dl);
}

}  // namespace rsvio
