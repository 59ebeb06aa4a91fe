// The marginalisation prior: what old keyframes and their points left behind, as a Gaussian on the
// keyframes still in the window (DSO, Engel et al. 2018, sec. 3.3; paper sec. IV-D).
//
// Contract
// - Normal-equation convention of the back end: energies E = sum w r^2; a term contributes
//   H = J^T W J and b = -J^T W r, and the step solves H dx = b (the factor 2 dropped throughout).
// - The prior is quadratic in the perturbation delta = x [-] x_lin of its keyframes from their
//   linearisation points (window.h: stateDelta; left perturbation of the pose):
//     E_m(delta) = delta^T H delta - 2 b^T delta,   contribution at x:  H,  b - H delta.
//   A keyframe's linearisation point is frozen when it first enters the prior (first-estimate
//   Jacobians): the prior is never relinearised, so its null space stays that of x_lin (DSO, Basalt).
// - addTerm(H_t, b_t): a term linearised at the CURRENT state x over some keyframes (e.g. marginalised
//   points after their own Schur complement) is re-expressed at x_lin: b += b_t + H_t delta, H += H_t.
// - marginalizeKeyframe(k): Schur complement of k's block, H' = H_rr - H_rk H_kk^+ H_kr,
//   b' = b_r - H_rk H_kk^+ b_k, H_kk^+ the pseudo-inverse (eigenvalues below 1e-12 x the largest are
//   dropped: directions nothing observed). Fixed dimensions (the gauge keyframe's pose and affine,
//   affine parameters that are not estimated) must be zero in added terms (the back end zeroes them):
//   their zero rows then drop out of the pseudo-inverse, which conditions on them as known values.
// - Keyframes are identified by Keyframe*; blocks are ordered by entry. All keyframes in the prior are
//   in the window. A block is the keyframe's full state (StateLayout::stateDim(): photometric, then
//   inertial when visual-inertial); a prior whose layout has global states ends with the global block
//   (T_Wm_Wf, time offset, line delay: StateLayout::globalDim()) of the GlobalStates given by
//   setGlobals(), whose linearisation point is frozen the first time a term reaches it. addTo() scatters the blocks to the window
//   system's photometric, inertial and global offsets (window.h).
#pragma once
#include <Eigen/Core>
#include <vector>

#include "rsvio/backend/window.h"

namespace rsvio {

class MarginalizationPrior {
 public:
  explicit MarginalizationPrior(StateLayout layout = {}) : layout_(layout) {}

  const StateLayout& layout() const { return layout_; }
  bool empty() const { return keyframes_.empty(); }
  const std::vector<Keyframe*>& keyframes() const { return keyframes_; }
  const Eigen::MatrixXd& H() const { return H_; }
  const Eigen::VectorXd& b() const { return b_; }
  int blockOf(const Keyframe* kf) const;  // -1 when kf has no block

  // Gives kf a block (zero information) and freezes its linearisation point at its current state,
  // unless it is frozen already (Keyframe::in_prior: the priors of dynamic_marginalization.h share it).
  void addKeyframe(Keyframe* kf);

  // The global states of the window (visual-inertial, estimated line delay; their delta enters the prior's).
  void setGlobals(GlobalStates* g);
  // The inertial state joins (visual-inertial initialisation): every block grows by an empty inertial
  // block and the global block by its empty inertial part (in front of the line delay). The shutter
  // and the line-delay estimation cannot change.
  void setLayout(const StateLayout& layout);

  // Adds a term linearised at the current states. H_t, b_t are over `kfs` (each kfDim() rows, or each
  // stateDim() rows, in that order), followed by the global block (globalDim() rows) when with_global;
  // keyframes without a block get one first.
  void addTerm(const std::vector<Keyframe*>& kfs, const Eigen::MatrixXd& H_t, const Eigen::VectorXd& b_t,
               bool with_global = false);

  // The same for a term whose keyframes are the window's only through points that scaled with them
  // (marginalised points): when project_scale is set, the monocular scale direction at the keyframes'
  // linearisation points (pose translation t_lin, twist velocity v_lin, the rest zero) is first
  // projected off H_t and b_t (H_t <- P H_t P, b_t <- P b_t, P = I - u u^T). H_t is linearised at the
  // current state, so its null direction is the scale at x, not at x_lin; summed with earlier terms it
  // would give the prior information on the scale, which the photometric energy does not have.
  // with_global: H_t, b_t end with the global block as in addTerm (its rows are not projected).
  void addScaleFreeTerm(const std::vector<Keyframe*>& kfs, const Eigen::MatrixXd& H_t, const Eigen::VectorXd& b_t,
                        bool project_scale, bool with_global = false);

  // Removes kf's block by the Schur complement (see the contract).
  void marginalizeKeyframe(Keyframe* kf);

  // The prior at the current states, over the blocks of the window order (window[i]->index == i):
  // adds H and b - H delta into H_win, b_win; returns E_m(delta).
  double addTo(Eigen::MatrixXd& H_win, Eigen::VectorXd& b_win) const;
  double energy() const;  // E_m(delta) at the current states

  // Stacked delta of every block at the current states (the global block last).
  Eigen::VectorXd delta() const;

 private:
  void ensureGlobalBlock();
  StateLayout layout_;
  GlobalStates* globals_ = nullptr;
  std::vector<Keyframe*> keyframes_;
  Eigen::MatrixXd H_;
  Eigen::VectorXd b_;
};

}  // namespace rsvio
