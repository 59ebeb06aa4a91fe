// The marginalisation prior (contract in rsvio/backend/marginalization.h).
#include "rsvio/backend/marginalization.h"

#include <Eigen/Eigenvalues>
#include <algorithm>

#include "rsvio/core/error.h"

namespace rsvio {

namespace {

// Inserts `d` zero rows and columns at position `at` of a symmetric system.
void insertZeros(Eigen::MatrixXd& H, Eigen::VectorXd& b, Eigen::Index at, Eigen::Index d) {
  const Eigen::Index n = H.rows();
  Eigen::MatrixXd Hn = Eigen::MatrixXd::Zero(n + d, n + d);
  Eigen::VectorXd bn = Eigen::VectorXd::Zero(n + d);
  const Eigen::Index tail = n - at;
  Hn.topLeftCorner(at, at) = H.topLeftCorner(at, at);
  Hn.topRightCorner(at, tail) = H.topRightCorner(at, tail);
  Hn.bottomLeftCorner(tail, at) = H.bottomLeftCorner(tail, at);
  Hn.bottomRightCorner(tail, tail) = H.bottomRightCorner(tail, tail);
  bn.head(at) = b.head(at);
  bn.tail(tail) = b.tail(tail);
  H.swap(Hn);
  b.swap(bn);
}

}  // namespace

int MarginalizationPrior::blockOf(const Keyframe* kf) const {
  for (size_t i = 0; i < keyframes_.size(); ++i)
    if (keyframes_[i] == kf) return static_cast<int>(i);
  return -1;
}

void MarginalizationPrior::setGlobals(GlobalStates* g) { globals_ = g; }

void MarginalizationPrior::setLayout(const StateLayout& layout) {
  if (layout.rolling != layout_.rolling) throw Error("MarginalizationPrior::setLayout: the shutter cannot change");
  if (layout.inertial == layout_.inertial && layout.globalDim() == layout_.globalDim()) {
    layout_ = layout;
    return;
  }
  if (layout_.inertial || layout.lineDelay() != layout_.lineDelay())
    throw Error("MarginalizationPrior::setLayout: only the inertial state can join");
  const int kd = layout_.kfDim();
  const Eigen::Index nb = static_cast<Eigen::Index>(keyframes_.size());
  // Each block grows by the (empty) inertial block after its photometric part, then the global block
  // by its (empty) inertial part in front of the line delay when the prior has that already.
  for (Eigen::Index i = nb - 1; i >= 0; --i) insertZeros(H_, b_, i * kd + kd, StateLayout::kImuDim);
  insertZeros(H_, b_, std::min<Eigen::Index>(nb * layout.stateDim(), H_.rows()), layout.inertialGlobalDim());
  layout_ = layout;
  if (globals_ && globals_->in_prior) {  // no information on the new entries yet: any point is exact
    globals_->lin.T_wm_wf = globals_->state.T_wm_wf;
    globals_->lin.time_offset_s = globals_->state.time_offset_s;
  }
}

void MarginalizationPrior::addKeyframe(Keyframe* kf) {
  if (blockOf(kf) >= 0) return;
  const int d = layout_.stateDim();
  insertZeros(H_, b_, static_cast<Eigen::Index>(keyframes_.size()) * d, d);
  keyframes_.push_back(kf);
  if (kf->in_prior) return;  // frozen already (by another prior of DynamicMarginalization)
  kf->in_prior = true;
  kf->lin = kf->state;  // first estimate, frozen from now on
}

void MarginalizationPrior::ensureGlobalBlock() {
  const Eigen::Index want = static_cast<Eigen::Index>(keyframes_.size()) * layout_.stateDim() + layout_.globalDim();
  if (H_.rows() < want) insertZeros(H_, b_, H_.rows(), want - H_.rows());
  if (layout_.globalDim() > 0 && globals_ && !globals_->in_prior) {
    globals_->in_prior = true;
    globals_->lin = globals_->state;  // first estimate, frozen from now on
  }
}

Eigen::VectorXd MarginalizationPrior::delta() const {
  const int d = layout_.stateDim();
  const int g = layout_.globalDim();
  Eigen::VectorXd x = Eigen::VectorXd::Zero(H_.rows());
  for (size_t i = 0; i < keyframes_.size(); ++i)
    x.segment(static_cast<Eigen::Index>(i) * d, d) = stateDelta(keyframes_[i]->state, keyframes_[i]->lin, layout_);
  if (g > 0 && globals_ && globals_->in_prior && H_.rows() >= static_cast<Eigen::Index>(keyframes_.size()) * d + g)
    x.tail(g) = globalDelta(globals_->state, globals_->lin, layout_);
  return x;
}

void MarginalizationPrior::addTerm(const std::vector<Keyframe*>& kfs, const Eigen::MatrixXd& H_t,
                                   const Eigen::VectorXd& b_t, bool with_global) {
  const int g = with_global ? layout_.globalDim() : 0;
  const Eigen::Index nk = static_cast<Eigen::Index>(kfs.size());
  if (H_t.cols() != H_t.rows() || b_t.size() != H_t.rows() || nk == 0 || (H_t.rows() - g) % nk != 0)
    throw Error("MarginalizationPrior::addTerm: term size does not match its keyframes");
  const int td = static_cast<int>((H_t.rows() - g) / nk);  // the term's block size per keyframe
  const int kd = layout_.kfDim(), d = layout_.stateDim();
  if (td != kd && td != d) throw Error("MarginalizationPrior::addTerm: term size does not match its keyframes");
  if (with_global && layout_.globalDim() == 0)
    throw Error("MarginalizationPrior::addTerm: the layout has no global block");
  for (Keyframe* kf : kfs) addKeyframe(kf);
  if (with_global || layout_.globalDim() > 0) ensureGlobalBlock();
  // Prior index of each of the term's rows.
  std::vector<Eigen::Index> idx(static_cast<size_t>(H_t.rows()));
  for (Eigen::Index i = 0; i < nk; ++i) {
    const Eigen::Index base = static_cast<Eigen::Index>(blockOf(kfs[static_cast<size_t>(i)])) * d;
    for (int r = 0; r < td; ++r) idx[static_cast<size_t>(i * td + r)] = base + r;
  }
  const Eigen::Index gbase = static_cast<Eigen::Index>(keyframes_.size()) * d;
  for (int r = 0; r < g; ++r) idx[static_cast<size_t>(nk * td + r)] = gbase + r;
  // b at the linearisation point: the term's gradient at x moved back along its own Hessian.
  const Eigen::VectorXd dall = delta();
  Eigen::VectorXd dl(H_t.rows());
  for (Eigen::Index r = 0; r < H_t.rows(); ++r) dl[r] = dall[idx[static_cast<size_t>(r)]];
  const Eigen::VectorXd b_lin = b_t + H_t * dl;
  for (Eigen::Index i = 0; i < H_t.rows(); ++i) {
    const Eigen::Index pi = idx[static_cast<size_t>(i)];
    b_[pi] += b_lin[i];
    for (Eigen::Index j = 0; j < H_t.rows(); ++j) H_(pi, idx[static_cast<size_t>(j)]) += H_t(i, j);
  }
}

void MarginalizationPrior::addScaleFreeTerm(const std::vector<Keyframe*>& kfs, const Eigen::MatrixXd& H_t,
                                            const Eigen::VectorXd& b_t, bool project_scale, bool with_global) {
  const int d = layout_.kfDim();
  const Eigen::Index g = with_global ? layout_.globalDim() : 0;
  if (!project_scale || H_t.rows() != static_cast<Eigen::Index>(kfs.size()) * d + g)
    return addTerm(kfs, H_t, b_t, with_global);
  for (Keyframe* kf : kfs) addKeyframe(kf);  // freezes x_lin of keyframes new to the prior
  // The global rows (the line delay: the scale does not change it) have no component along the scale.
  Eigen::VectorXd n = Eigen::VectorXd::Zero(H_t.rows());
  for (size_t i = 0; i < kfs.size(); ++i)
    scaleDirection(kfs[i]->lin, layout_, n.segment(static_cast<Eigen::Index>(i) * d, d));
  Eigen::MatrixXd H_p = H_t;
  Eigen::VectorXd b_p = b_t;
  if (!projectOffDirection(n, H_p, b_p)) return addTerm(kfs, H_t, b_t, with_global);
  addTerm(kfs, H_p, b_p, with_global);
}

void MarginalizationPrior::marginalizeKeyframe(Keyframe* kf) {
  const int k = blockOf(kf);
  if (k < 0) return;
  const int d = layout_.stateDim();
  const Eigen::Index n = H_.rows();
  // Permutation: keep = every other block (and the global block), in order.
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
  if (H_.rows() == 0) return 0.0;
  const Eigen::VectorXd dl = delta();
  return dl.dot(H_ * dl) - 2.0 * b_.dot(dl);
}

double MarginalizationPrior::addTo(Eigen::MatrixXd& H_win, Eigen::VectorXd& b_win) const {
  if (H_.rows() == 0) return 0.0;
  const int d = layout_.stateDim(), kd = layout_.kfDim(), g = layout_.globalDim();
  const int nw = static_cast<int>((H_win.rows() - g) / layout_.stateDim());  // keyframes in the window
  // Window index of each prior row.
  std::vector<Eigen::Index> idx(static_cast<size_t>(H_.rows()));
  for (size_t i = 0; i < keyframes_.size(); ++i) {
    const int wi = keyframes_[i]->index;
    const Eigen::Index base = static_cast<Eigen::Index>(i) * d;
    for (int r = 0; r < kd; ++r) idx[static_cast<size_t>(base + r)] = layout_.photometricOffset(wi) + r;
    for (int r = kd; r < d; ++r) idx[static_cast<size_t>(base + r)] = layout_.imuOffset(wi, nw) + (r - kd);
  }
  const Eigen::Index gbase = static_cast<Eigen::Index>(keyframes_.size()) * d;
  for (Eigen::Index r = gbase; r < H_.rows(); ++r) idx[static_cast<size_t>(r)] = layout_.globalOffset(nw) + (r - gbase);
  const Eigen::VectorXd dl = delta();
  const Eigen::VectorXd b_cur = b_ - H_ * dl;
  for (Eigen::Index i = 0; i < H_.rows(); ++i) {
    const Eigen::Index wi = idx[static_cast<size_t>(i)];
    b_win[wi] += b_cur[i];
    for (Eigen::Index j = 0; j < H_.rows(); ++j) H_win(wi, idx[static_cast<size_t>(j)]) += H_(i, j);
  }
  return dl.dot(H_ * dl) - 2.0 * b_.dot(dl);
}

}  // namespace rsvio
