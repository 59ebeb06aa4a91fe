// A smooth-motion prior on the rolling-shutter twists inside the window optimisation (paper sec. IV-C:
// "[7] stabilises the system by a prior for the twist that assumes a smooth motion between keyframes";
// Schubert et al., ECCV 2018). Without it the twist is nearly unobservable from a few keyframes alone
// and the bundle adjustment drives it wherever noise pushes (docs/rolling_shutter.md, measured).
//
// Contract
// - Each keyframe k has at most one term, over its motion neighbours a = Keyframe::motion_prev and
//   b = Keyframe::motion_next (either may be k itself when it has no such neighbour):
//     r_k = xi_k - log(T_b T_a^-1) / (t_b - t_a)                        (6-vector, per second)
//   T = T_c_w^0 central poses (world W_f -> camera), xi per second (translation; rotation), as
//   window.h. With both neighbours it is the central difference of the optimised neighbour poses;
//   a keyframe that is the newest (no next yet) gets the backward difference, the first keyframe of a
//   run the forward one.
// - Energy r^T W r, W = information * min(1, (gap_ref_s / (t_b - t_a))^2) * Keyframe::motion_weight,
//   the rotation rows (3-5) also * Keyframe::motion_weight_rot: the constant-twist assumption
//   degrades with the time the difference spans; a keyframe whose twist the IMU measures (twist
//   energy) may weigh it less (InertialOptions::smooth_motion_weight), or its rotation alone before
//   the initialisation (InertialOptions::smooth_motion_rot_weight_before_init).
// - Jacobians (LEFT pose perturbations T <- exp(d) T, rsvio/lie/lie.h; twists additive), with
//   u = log(T_b T_a^-1), D = t_b - t_a:
//     d r / d xi_k = I,   d r / d T_b = -Jl^-1(u) / D,   d r / d T_a = +Jr^-1(u) / D
//   (T_b T_a^-1 -> exp(d_b) T_b T_a^-1 exp(-d_a)). Blocks of the same keyframe add up.
// - Lifetime (the owner, system/, keeps it): a keyframe gets its term when it enters the window
//   (motion_prev = the newest keyframe then); the previous newest keyframe's term gains its next
//   neighbour at that moment. When any keyframe of a term leaves the window, the term is linearised
//   at the current states into the marginalisation prior and switched off (motion_term = false), so
//   every term is counted once and no term points at a keyframe that left.
// - Scale: the residual's translation scales with the monocular scale, so the term is handed to the
//   prior scale-free (MarginalizationPrior::addScaleFreeTerm), as marginalised points are.
#pragma once
#include <Eigen/Core>
#include <vector>

#include "rsvio/backend/bundle_adjustment.h"

namespace rsvio {

struct SmoothMotionOptions {
  Mat6 information = Mat6::Zero();  // diag(info_trans x3 [s^2/unit^2], info_rot x3 [s^2/rad^2])
  double gap_ref_s = 0.25;          // spans longer than this weigh less (quadratically)
};

class SmoothMotionTerm : public WindowTerm {
 public:
  explicit SmoothMotionTerm(const SmoothMotionOptions& o) : o_(o) {}

  // Every active term of the window (rolling layouts only; a global layout has no twist: energy 0).
  double linearize(const KeyframeList& window, const StateLayout& layout, Eigen::MatrixXd& H,
                   Eigen::VectorXd& b) const override;

  // The term of keyframe k alone: the keyframes it involves (distinct, window order) and its H, b over
  // them (kfDim() blocks each). Returns its energy; 0 and no keyframes when k has no active term.
  double linearizeOne(const Keyframe& k, const StateLayout& layout, std::vector<Keyframe*>* kfs, Eigen::MatrixXd* H,
                      Eigen::VectorXd* b) const;

  // Residual and the three Jacobians (xi_k, T_a, T_b) of k's term, and its weight; false when none.
  struct Eval {
    Vec6 r = Vec6::Zero();
    Mat6 d_r_d_xi = Mat6::Identity();
    Mat6 d_r_d_Ta = Mat6::Zero();
    Mat6 d_r_d_Tb = Mat6::Zero();
    Mat6 W = Mat6::Zero();
    const Keyframe* a = nullptr;
    const Keyframe* b = nullptr;
  };
  bool evaluate(const Keyframe& k, Eval* e) const;

  const SmoothMotionOptions& options() const { return o_; }

 private:
  SmoothMotionOptions o_;
};

}  // namespace rsvio
