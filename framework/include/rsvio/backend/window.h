// The optimisation window of the photometric back end: keyframes, their active points and the points'
// observations (paper sec. IV-A, eq. 8: E_ph = sum over keyframes i, points p hosted in i, targets j).
//
// Contract
// - A keyframe's state (paper eq. 6): central pose T_c_w^0 (world W_f -> camera at the image timestamp,
//   raw row y0), affine brightness (a, b) and, when the shutter is rolling, the twist xi per second
//   (translation; rotation), T_c_w(t) = exp(xi t) T_c_w^0. Poses are perturbed on the LEFT,
//   T <- exp(delta) T (rsvio/lie/lie.h); a, b and the twist additively.
// - Normal-equation blocks (StateLayout), n keyframes in window order (oldest first):
//     [ photometric block of kf 0 .. n-1 ][ inertial block of kf 0 .. n-1 ][ global block ]
//   photometric block (kfDim()): pose [0, 6), affine (a, b) [6, 8), twist [8, 14) when rolling;
//   inertial block (kImuDim = 9, visual-inertial only): IMU velocity v in W_m [0, 3), gyro bias [3, 6),
//   accelerometer bias [6, 9) (additive); global block (globalDim()): T_Wm_Wf as (omega; sigma), LEFT
//   perturbation of RxSO3 (sigma = log scale) [0, 4), then the camera-IMU time offset in seconds [4]
//   when it is estimated (visual-inertial only), then the rolling shutter's line delay in seconds per
//   row (additive) when it is estimated (lineDelayIndex(); visual odometry too, where it is the whole
//   global block). The points couple to photometric blocks and, through the line delay, to that one
//   global entry; the photometric kernels keep their fixed block size; a keyframe's full state
//   (stateDim(): photometric then inertial) is contiguous in the marginalisation prior.
// - A point is hosted by a keyframe at an integer level-0 pixel (u, v) of its RAW image, with the unit
//   bearing of that pixel and its inverse depth rho = 1 / distance along the bearing; it is fixed in
//   the world at the host row's capture time (rs_projection.h, "host-frame points").
// - A point has at most one observation per target keyframe (never in its host).
// - Keyframes are owned by the window (unique_ptr), so Keyframe* stays valid until the keyframe leaves;
//   `index` is the keyframe's current position in the window and changes when older ones leave.
#pragma once
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include "rsvio/frontend/candidate_points.h"
#include "rsvio/interfaces/motion_prior.h"
#include "rsvio/lie/rxso3.h"
#include "rsvio/lie/se3.h"
#include "rsvio/photometric/image_pyramid.h"
#include "rsvio/photometric/photometric_residual.h"

namespace rsvio {

class ImuFactor;

struct KeyframeState {
  SE3d T_c_w;                 // central pose, camera from world (W_f)
  AffineBrightness affine;
  Vec6 twist = Vec6::Zero();  // per second; optimised only with a rolling shutter
  // Visual-inertial only: IMU velocity in the metric world W_m [m/s], biases [rad/s], [m/s^2].
  Vec3 v_wm = Vec3::Zero();
  Vec3 bias_gyro = Vec3::Zero();
  Vec3 bias_accel = Vec3::Zero();
};

// The window's global states: visual-inertial, the scale-gravity transform T_Wm_Wf (paper eq. 2,
// p_Wm = s R_g p_Wf) and the camera-IMU time offset t_imu = t_cam + time_offset_s (Kalibr's sign);
// rolling shutter with estimate_line_delay, the line delay (s per raw row, RowTiming::line_delay_s).
struct GlobalState {
  RxSO3d T_wm_wf;
  double time_offset_s = 0.0;
  double line_delay_s = 0.0;
};

struct GlobalStates {
  GlobalState state, backup, lin;  // as KeyframeState: current, LM backup, frozen linearisation point
  bool in_prior = false;           // the marginalisation prior has the global block
};

// Layout of the normal equations (see the contract).
struct StateLayout {
  static constexpr int kPose = 0;
  static constexpr int kAffine = 6;
  static constexpr int kTwist = 8;
  static constexpr int kImuDim = 9;
  static constexpr int kVel = 0, kBiasGyro = 3, kBiasAccel = 6;  // inside the inertial block
  static constexpr int kGlobalRot = 0, kGlobalScale = 3, kGlobalOffset = 4;  // inside the global block
  bool rolling = false;
  bool inertial = false;
  bool estimate_time_offset = false;  // inertial only
  bool estimate_line_delay = false;   // rolling only
  int kfDim() const { return rolling ? 14 : 8; }  // photometric block
  int imuDim() const { return inertial ? kImuDim : 0; }
  int stateDim() const { return kfDim() + imuDim(); }  // a keyframe's full state
  // The global block: the inertial part (T_Wm_Wf, time offset), then the line delay.
  int inertialGlobalDim() const { return inertial ? (estimate_time_offset ? 5 : 4) : 0; }
  bool lineDelay() const { return rolling && estimate_line_delay; }
  int globalDim() const { return inertialGlobalDim() + (lineDelay() ? 1 : 0); }
  int lineDelayIndex() const { return inertialGlobalDim(); }  // inside the global block (when lineDelay())
  // Offsets in the window system of n keyframes.
  int photometricOffset(int k) const { return k * kfDim(); }
  int imuOffset(int k, int n) const { return n * kfDim() + k * kImuDim; }
  int globalOffset(int n) const { return n * (kfDim() + imuDim()); }
  int windowDim(int n) const { return n * stateDim() + globalDim(); }
};

// kIn: used; kOob: the projection left the image or failed; kOutlier: energy above the outlier energy.
enum class ObsState : uint8_t { kIn, kOob, kOutlier };

struct Keyframe;

struct ActiveObservation {
  Keyframe* target = nullptr;
  ObsState state = ObsState::kIn;
  float energy = 0.f;           // at the last evaluation
  // The last evaluation, kept for the diagnostics log (io/diagnostics_log.h).
  float u = 0.f, v = 0.f;       // projected centre in the target, raw level-0 pixels
  float grad_u = 0.f, grad_v = 0.f;
  float mean_residual = 0.f;
  float mean_weight = 0.f;
};

struct ActivePoint {
  Keyframe* host = nullptr;
  int64_t id = 0;               // unique over the run (deterministic order of creation)
  float u = 0.f, v = 0.f;       // host pixel, level 0 (integers for selected points)
  Vec3 bearing = Vec3::UnitZ(); // unit bearing of (u, v) in the host camera
  Eigen::Matrix<double, 3, 2> d_bearing_d_uv = Eigen::Matrix<double, 3, 2>::Zero();
  double idepth = 1.0;          // 1 / distance along the bearing
  double idepth_hessian = 0.0;  // information of rho at the last linearisation (no damping)
  PatternHost pattern;          // host intensities and gradient weights of the 8-pixel pattern
  std::vector<ActiveObservation> obs;

  int numIn() const {
    int n = 0;
    for (const ActiveObservation& o : obs) n += o.state == ObsState::kIn;
    return n;
  }
};

struct Keyframe {
  int64_t frame_index = 0;      // position in the input sequence
  int64_t t_ns = 0;             // image timestamp (row y0)
  int64_t kf_id = 0;            // counts keyframes over the run
  int index = -1;               // position in the window
  double exposure_ms = std::numeric_limits<double>::quiet_NaN();
  std::shared_ptr<const ImagePyramid> pyramid;

  KeyframeState state;
  KeyframeState backup;         // LM: state before the trial step
  KeyframeState lin;            // linearisation point, frozen once the keyframe is in the prior (FEJ)
  bool in_prior = false;        // the marginalisation prior has a block for this keyframe
  bool gauge = false;           // pose and affine fixed (the first keyframe: fixes the gauge)

  bool has_twist_prior = false; // paper eq. 33 or a smooth-motion prior (motion_prior.h)
  TwistPrior twist_prior;
  Vec6 twist_start = Vec6::Zero();  // where twist_regularization pulls when there is no prior
  // Smooth-motion term inside the optimisation (backend/smooth_motion_term.h): the keyframe's motion
  // neighbours (nullptr: none) and whether its term is still active (false once marginalised).
  bool motion_term = false;
  double motion_weight = 1.0;  // multiplies the term's information (set when the keyframe is made)
  double motion_weight_rot = 1.0;  // multiplies its rotation rows as well (the gyroscope holds them)
  Keyframe* motion_prev = nullptr;
  Keyframe* motion_next = nullptr;
  // Visual-inertial terms (backend/inertial_term.h): the IMU factor from imu_prev to this keyframe,
  // preintegrated over [imu_prev->t_ns, t_ns] (camera clock), active while imu_term is set; the
  // gyroscope reading at this keyframe's time for its twist energy (paper eq. 33), active while
  // twist_energy is set. Both are switched off once the terms went into the marginalisation prior.
  bool imu_term = false;
  Keyframe* imu_prev = nullptr;
  std::shared_ptr<const ImuFactor> imu_factor;
  bool twist_energy = false;
  Vec3 gyro_at_t = Vec3::Zero();
  // Rolling shutter: the rate of change of the twist's rotation at t_ns (rad/s^2), from the gyroscope
  // (imu.readout_angular_acceleration), known and not optimised: the rows' rotation to second order
  // (RsFrame::w_dot, geometry/rs_projection.h). Zero otherwise.
  Vec3 w_dot = Vec3::Zero();

  std::vector<ActivePoint> points;         // active points hosted here
  std::vector<CandidatePoint> candidates;  // waiting for activation (frontend/candidate_points.h)
  int points_out = 0;                      // points that left (dropped or marginalised): DSO's "out"
  bool flagged_for_marg = false;
  // Twist seen from the neighbouring frames' poses (d T / dt, per second), for the diagnostics log of
  // a global-shutter run; set once the next frame is tracked.
  bool has_observed_twist = false;
  Vec6 observed_twist = Vec6::Zero();
};

using KeyframeList = std::vector<std::unique_ptr<Keyframe>>;

// Renumbers Keyframe::index after the window changed.
inline void reindex(KeyframeList& window) {
  for (size_t i = 0; i < window.size(); ++i) window[i]->index = static_cast<int>(i);
}

// Perturbation of a keyframe's full state (stateDim(): photometric block, then inertial block) from its
// linearisation point: pose log(T T_lin^-1) (left), affine a - a_lin, b - b_lin, twist xi - xi_lin,
// v - v_lin, b_g - b_g,lin, b_a - b_a,lin.
Eigen::VectorXd stateDelta(const KeyframeState& x, const KeyframeState& lin, const StateLayout& layout);

// Applies a full-state step (stateDim(), the order above): T <- exp(d) T, the rest additive.
void applyStep(KeyframeState& x, const Eigen::Ref<const Eigen::VectorXd>& step, const StateLayout& layout);

// The same for the global block (globalDim()): T_Wm_Wf <- exp(omega, sigma) T_Wm_Wf, offset and line
// delay additive; the delta is log(T T_lin^-1), x - x_lin.
Eigen::VectorXd globalDelta(const GlobalState& x, const GlobalState& lin, const StateLayout& layout);
void applyGlobalStep(GlobalState& x, const Eigen::Ref<const Eigen::VectorXd>& step, const StateLayout& layout);

// The monocular scale direction over one keyframe's photometric block (kfDim() rows, written into
// kf_block): d/ds at s = 1 of scaling W_f about its origin by s, in the left-perturbation coordinates
// above: the pose translation t and the twist velocity v (rolling), zero elsewhere. (The points'
// inverse depths move by -rho and T_Wm_Wf's log-scale by -1; those rows are not in this block.)
void scaleDirection(const KeyframeState& x, const StateLayout& layout, Eigen::Ref<Eigen::VectorXd> kf_block);

// Projects the unit direction u = n / |n| off a quadratic term: H <- P H P, b <- P b, P = I - u u^T, so
// the term has neither gradient nor curvature along n. Returns false (nothing changed) when n is zero.
bool projectOffDirection(const Eigen::VectorXd& n, Eigen::MatrixXd& H, Eigen::VectorXd& b);

// A keyframe's full state step gathered from the window system (photometric and inertial blocks).
Eigen::VectorXd gatherState(const Eigen::VectorXd& x_win, int k, int n, const StateLayout& layout);

}  // namespace rsvio
