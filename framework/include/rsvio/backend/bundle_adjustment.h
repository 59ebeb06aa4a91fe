// Windowed photometric bundle adjustment (paper sec. IV-A and IV-D, eqs. 8 and 34 without the IMU
// terms; DSO, Engel et al. 2018, sec. 3.2): Levenberg-Marquardt over the keyframe states of the
// window (pose, affine brightness, twist when rolling) and the inverse depths of the active points.
//
// Contract
// - Energy E = sum over active points p, targets j of the pattern energy (photometric_residual.h:
//   Huber, gradient weights), + the marginalisation prior + keyframe priors (affine a, b to 0 with the
//   photometric model's strengths; twist prior from the motion prior, or twist_regularization) + any
//   WindowTerm (e.g. IMU factors, later). Normal equations H dx = b with H = J^T W J, b = -J^T W r.
// - Residuals: every target pixel comes from the rolling-shutter projection of the host point
//   (rs_projection.h; a global shutter takes the same path with dt/dv = 0), so the Jacobians include
//   d(row)/d(state). The pattern is placed in the target with the point's local warp W = d p'/d p
//   (photometric_residual.h) and evaluated on pyramid level 0.
// - Observation states: an observation whose projection fails or leaves the image is kOob, one whose
//   energy exceeds the outlier energy is kOutlier; both add that constant energy (so energies of
//   trial steps stay comparable) and no derivative. The states of the final accepted linearisation
//   are written back to the observations; removing them is the caller's decision (PointManager).
// - Schur complement: each point's inverse depth couples only its host and its targets, so H_pp is
//   1x1 per point and the reduced camera system H_cc - sum_p h_p h_p^T / H_pp is formed block-wise
//   and solved by the solver plugin's solveDense(). When the solver prefersFullSystem(), the full
//   sparse system (cameras and points) goes to solveSparse() instead; both give the same step.
// - Damping: H_ii <- H_ii (1 + lambda) on every diagonal entry (cameras and points, before the Schur
//   complement), lambda x 0.5 after an accepted step and x 4 after a rejected one (then the step is
//   re-solved from the kept linearisation). A step is accepted when the total energy decreases.
// - Fixed dimensions (the gauge keyframe's pose and a, b; a, b of every keyframe when affine
//   brightness is not estimated) get zero rows and a unit diagonal: their step is 0.
// - Gauge: pose and a, b of a keyframe with Keyframe::gauge are fixed; the monocular scale is a null
//   direction that every step is projected off (fix_scale_gauge), so the steps never change it. With
//   the inertial state the W_f scale stays a null direction together with the scale of T_Wm_Wf
//   (scaling W_f by 1 + e and s by 1 / (1 + e) changes no residual): the projection then includes
//   sigma = log s, so the steps change the metric scale through s only; the yaw of T_Wm_Wf (omega_z,
//   unobservable: visual_inertial_factor.h) is a fixed dimension.
// - Determinism and threads: residuals are evaluated per host-target pair and accumulated per block
//   of points into their own partial sums, added in block order: the result is identical for 1 and 2
//   threads. No allocation per residual; buffers are reused across iterations.
#pragma once
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <memory>
#include <string>
#include <vector>

#include "rsvio/backend/backend_options.h"
#include "rsvio/backend/marginalization.h"
#include "rsvio/backend/window.h"
#include "rsvio/geometry/rs_projection.h"
#include "rsvio/photometric/photometric_residual.h"

namespace rsvio {

class CameraModel;
class SolverBackend;
class BlockRunner;

// A term over keyframe and global states only (no points): priors, IMU factors, the twist energy.
class WindowTerm {
 public:
  virtual ~WindowTerm() = default;
  // Adds J^T W J and -J^T W r at the current states into H, b (the window system of window.h:
  // StateLayout's photometric, inertial and global offsets); returns the energy.
  virtual double linearize(const KeyframeList& window, const StateLayout& layout, Eigen::MatrixXd& H,
                           Eigen::VectorXd& b) const = 0;
};

struct BundleAdjustmentConfig {
  StateLayout layout;
  ResidualOptions residual;
  bool estimate_affine = true;     // photometric.affine configured
  double affine_prior_a = 0.0;     // information pulling a to 0 (the model's)
  double affine_prior_b = 0.0;
  double lambda_initial = 1e-4;
  double step_threshold = 1e-4;    // relative energy decrease that ends the iterations
  // Consecutive rejected LM steps that end the iterations (0: only max_iterations and step_threshold
  // end them). A rejected step's relative damping (1e-4 x 4^k) barely changes the next step, so
  // further tries mostly repeat it (docs/performance.md, "Rejected steps").
  int max_rejected_steps = 0;
  // DSO's setting_forceAceptStep: every step is taken, whatever the energy does; the iterations end on
  // max_iterations or the small-step stop only (not on step_threshold or rejections).
  bool accept_all_steps = false;
  // The small-step stop: after an accepted step, stop when the RMS over the window's keyframes of the
  // pose step's rotation (rad) and of its translation times the points' mean inverse depth (rad: the
  // translation seen at the mean depth) are both below min_step_rad (DSO's test in doStepFromBackup;
  // its setting_thOptIterations 1.2 gives 6e-5), and the points' RMS inverse-depth step is below
  // min_step_idepth times their mean inverse depth (DSO does not test the depths; without that test one
  // of nine gs_vo runs at 800 points ended 0.47 m off, docs/performance.md "Small steps"). min_step_rad
  // 0: no such stop. Affine, twist, inertial and global (line delay, T_Wm_Wf) steps are not tested.
  double min_step_rad = 0.0;
  double min_step_idepth = 0.01;
  double twist_regularization = 1e-6;
  // Monocular runs: remove the scale direction (a null direction of the photometric energy) from every
  // step, so the damping cannot move the scale (DSO orthogonalises its steps the same way). Off when
  // a term makes the scale observable (IMU).
  bool fix_scale_gauge = true;
  // An estimated line delay is held (a fixed dimension) until the newest keyframe's kf_id + 1 (the
  // keyframes made over the run) reaches this: in the first windows after the monocular start the
  // twists are barely tied to the poses and the delay, seen only through line_delay x twist, runs away
  // (measured on tiny_rs: 59 -> 750 us at 2 keyframes). Odometry sets it from
  // backend.line_delay_hold_keyframes; the default is that option's.
  int line_delay_min_keyframes = BackendOptions{}.line_delay_hold_keyframes;
  int threads = 1;                 // 1 or 2
  // Rolling shutter: false forms every observation's host-pose Jacobian and accumulates it (the
  // reference the tests check the default against; slower). true (default): the host pose's blocks
  // from the target pose's through the pair's adjoint, as for a global shutter (ba_accumulate.cpp,
  // accumulateChunkRolling; docs/rolling_shutter.md "Cost").
  bool host_blocks_from_adjoint = true;
};

struct BundleAdjustmentStats {
  int iterations = 0;              // linearisations after the first
  int accepted = 0;
  int rejected = 0;                // steps whose energy was not lower (= iterations - accepted)
  bool small_step = false;         // the iterations ended on min_step_rad
  double energy_initial = 0.0;     // total energy before / after
  double energy_final = 0.0;
  double photometric_energy = 0.0; // inlier photometric energy at the end
  int num_obs = 0, num_in = 0, num_oob = 0, num_outlier = 0;
  double lambda = 0.0;
  bool solver_failed = false;
  std::string message;             // solver message when it failed
  double rmse() const { return num_in > 0 ? std::sqrt(photometric_energy / (num_in * double(kPatternSize))) : 0.0; }
  double inlierRatio() const { return num_obs > 0 ? static_cast<double>(num_in) / num_obs : 0.0; }
};

class BundleAdjuster {
 public:
  BundleAdjuster(const BundleAdjustmentConfig& config, const CameraModel& camera, const RowTiming& timing,
                 SolverBackend& solver);
  ~BundleAdjuster();
  BundleAdjuster(const BundleAdjuster&) = delete;
  BundleAdjuster& operator=(const BundleAdjuster&) = delete;

  const BundleAdjustmentConfig& config() const { return config_; }
  void setTerms(std::vector<const WindowTerm*> terms) { terms_ = std::move(terms); }
  // Visual-inertial: the layout gains the inertial and global blocks at the initialisation (the shutter
  // cannot change), and the global states the steps update (backup and restore as the keyframes').
  void setConfig(const BundleAdjustmentConfig& config);
  void setGlobals(GlobalStates* globals);

  // Levenberg-Marquardt on the window (see the contract). Observation states and the points'
  // idepth_hessian are updated from the final linearisation.
  BundleAdjustmentStats optimize(KeyframeList& window, const MarginalizationPrior& prior, int max_iterations);

  // Evaluates every observation at the current states (no step): states, energies and the diagnostics
  // fields of the observations, idepth_hessian of the points.
  BundleAdjustmentStats evaluate(KeyframeList& window, const MarginalizationPrior& prior);

  // Optimises only the inverse depths of `points` with every keyframe state held (DSO's
  // optimizeImmaturePoint before activation): per-point Gauss-Newton, a step kept only where the point's
  // energy decreased (else halved, up to `iterations` tries). Observation states and idepth_hessian
  // come from the final evaluation.
  void optimizeDepths(KeyframeList& window, const std::vector<ActivePoint*>& points, int iterations);

  // The marginalisation term of `points` (all their kIn observations) at the current states: the
  // points' Schur complement over the window blocks (window order), times `weight`, with fixed
  // dimensions zeroed. Returns the blocks that received information (window indices, ascending) and
  // the term restricted to them.
  void pointsTerm(const KeyframeList& window, const std::vector<ActivePoint*>& points, double weight,
                  std::vector<int>* blocks, Eigen::MatrixXd* H, Eigen::VectorXd* b);

  // Keyframe-only priors of one keyframe (affine, twist) at the current state, kfDim() block, with
  // fixed dimensions zeroed (for the marginalisation of that keyframe).
  void keyframePriorTerm(const Keyframe& kf, Eigen::MatrixXd* H, Eigen::VectorXd* b) const;

  // --- For tests: the system of the current linearisation.
  // Linearises at the current states (prior and terms included). Returns the total energy.
  double linearize(KeyframeList& window, const MarginalizationPrior& prior);
  // Solves one damped step from the last linearisation by the Schur complement (full = false) or the
  // full sparse system (full = true). dx_c: camera step (window block order); dx_p: inverse-depth
  // steps in the order of points() below. Returns false when the solver refuses.
  bool solveStep(double lambda, bool full, Eigen::VectorXd* dx_c, Eigen::VectorXd* dx_p, std::string* message = nullptr);
  // The full dense Hessian and right-hand side (cameras first, then points in points() order), undamped,
  // fixed dimensions masked.
  void fullSystem(Eigen::MatrixXd* H, Eigen::VectorXd* b) const;
  const std::vector<ActivePoint*>& points() const;

  struct Impl;

 private:
  BundleAdjustmentConfig config_;
  const CameraModel& camera_;
  RowTiming timing_;
  SolverBackend& solver_;
  std::vector<const WindowTerm*> terms_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rsvio
