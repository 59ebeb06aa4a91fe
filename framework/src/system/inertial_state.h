// The inertial part of the estimator (paper sec. IV, Fig. 3): the IMU buffer, the global states
// T_Wm_Wf and time offset, each keyframe's IMU factor and twist energy, the visual-inertial
// initialisation and the inertial divergence tests. Odometry composes it with the window; it never
// reads ground truth.
//
// Owns and keeps true
// - Before initialised(): the run is visual odometry; keyframes carry no inertial terms and the
//   window's layout has no inertial blocks. tryInitialize() (at each new keyframe, on the run's
//   keyframe poses so far) either keeps it so and records why (status()), or sets T_Wm_Wf, every
//   window keyframe's velocity and biases, links IMU factors between consecutive window keyframes and
//   switches the bundle adjuster and the prior to the inertial layout, once.
// - After: every keyframe entering the window gets the IMU factor from the newest keyframe and, with a
//   rolling shutter and an IMU twist Sigma, its twist energy; velocity, biases and twist start at the
//   IMU's prediction. A keyframe's terms go into the marginalisation prior before it leaves
//   (marginalizeTerms), so no term refers to a keyframe that left.
// - Times: keyframe stamps are camera times (middle row); IMU samples are picked at
//   t_imu = t_cam + time offset (Kalibr's sign), the current estimate when it is estimated.
// - The IMU buffer keeps the last buffer_s seconds (bounded memory on long runs).
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "rsvio/backend/bundle_adjustment.h"
#include "rsvio/backend/inertial_term.h"
#include "rsvio/backend/dynamic_marginalization.h"
#include "rsvio/backend/window.h"
#include "rsvio/imu/imu_buffer.h"
#include "rsvio/imu/inertial_options.h"
#include "rsvio/imu/vi_init.h"
#include "rsvio/interfaces/motion_prior.h"

namespace rsvio {

class InertialState {
 public:
  // twist_sigma_*: the IMU twist energy's Sigma (MotionPrior::twistEnergySigma); <= 0: no twist energy.
  // globals: the window's global states (KeyframeWindow::globals()), which hold T_Wm_Wf and the time
  // offset beside an estimated line delay; they must outlive this.
  InertialState(const InertialOptions& o, const SensorSetup& sensors, bool rolling, double twist_sigma_trans_m_s,
                double twist_sigma_rot_rad_s, GlobalStates& globals);

  // A fresh state for a restarted start (Odometry::Impl::restart) on the new window's globals: the same
  // options and sensors, this one's IMU buffer; nothing else (not initialised, no refusals).
  std::unique_ptr<InertialState> restarted(GlobalStates& globals) const;
  bool enabled() const { return o_.enabled; }
  bool initialised() const { return initialised_; }
  const std::string& status() const { return status_; }  // why it is not initialised yet (or "initialised")
  // Attempts that had enough data and were refused or rejected (the keyframe poses did not fit the
  // IMU, or the solution was implausible), and the first of them with the newest keyframe's time: why
  // an initialisation came late (report.json extra.vio).
  int refusals() const { return refusals_; }
  const std::string& firstRefusal() const { return first_refusal_; }
  int64_t firstRefusalNs() const { return first_refusal_t_ns_; }
  const InertialOptions& options() const { return o_; }

  void addImu(const ImuSample& s);

  // A keyframe enters the window; `newest` is the newest keyframe before it (null: none). After the
  // initialisation: links its IMU factor and twist energy and starts its inertial state at the IMU's
  // prediction from `newest`. Returns a warning when the IMU does not cover the interval ("" if fine).
  std::string onNewKeyframe(Keyframe& kf, Keyframe* newest);

  // Tries the visual-inertial initialisation (see the contract) with the keyframe poses of the run so
  // far (time order, T_Cf_Wf). Returns true when it succeeded now.
  bool tryInitialize(const std::vector<ViInitKeyframe>& keyframes, KeyframeList& window, BundleAdjuster& ba,
                     DynamicMarginalization& prior);

  // Before `leaving` leaves the window: its terms (and the factor from it) into the prior, switched off.
  // The terms depend on the scale: they go to the priors of dynamic marginalisation that keep such terms.
  void marginalizeTerms(Keyframe& leaving, const KeyframeList& window, DynamicMarginalization& prior) const;

  // After an optimisation: re-preintegrates the factors whose bias or offset moved too far.
  void refreshFactors(KeyframeList& window);
  // "" or the reason the estimate diverged (bias runaway, scale collapse, exploding IMU residuals, IMU
  // residuals that stay high). Call once after each keyframe's optimisation: it records the window's IMU
  // energy each time (the run's level, the stretch above it, residualWarning).
  std::string checkDivergence(const KeyframeList& window);
  // "" or a warning that the window's IMU energy stayed high over the run (InertialOptions::warn_imu_chi2).
  std::string residualWarning() const;

  // The inertial part of a tracked frame's motion state, propagated from keyframe `ref` to t_ns.
  void fillMotionState(const Keyframe& ref, MotionState* ms) const;
  // Rolling shutter with options().frame_twist_from_imu, after the initialisation: the IMU's twist of a
  // frame at camera time t_ns >= ref.t_ns (eq. 32, per second, left of T_Cf_Wf): the gyroscope
  // interpolated at t_ns + offset less ref's gyro bias, ref's velocity propagated to t_ns, the rotation
  // of T_c_w (the frame's pose or a guess of it). Before it, with
  // options().frame_rotation_from_gyro_before_init: only xi's rotation, -R_Cm_I (gyro - b_g). False
  // (xi untouched) otherwise or without IMU data over [ref.t_ns, t_ns] on the IMU clock.
  bool frameTwist(const Keyframe& ref, int64_t t_ns, const SE3d& T_c_w, Vec6* xi) const;
  // The camera's rotation rate from the gyroscope at camera time t_ns (the rotation part of a twist,
  // left of T_Cf_Wf: -R_Cm_I (gyro - b_g), rad/s) with the gyro bias b_g given. Needs no scale or
  // gravity, so it serves before the initialisation. False without an IMU sample around t_ns + offset.
  bool gyroRate(int64_t t_ns, const Vec3& bias_gyro, Vec3* w) const;
  // The camera's rotation from camera time t0_ns to t1_ns by the gyroscope (bias b_g given): camera
  // coordinates of a static point at t1 are R_1_0 times those at t0 (the rates of gyroRate integrated
  // at their midpoints over steps of at most 5 ms, the newest step on the left). False without IMU
  // samples over the span.
  bool gyroRotation(int64_t t0_ns, int64_t t1_ns, const Vec3& bias_gyro, SO3d* R_1_0) const;
  // Rolling shutter with options().readout_angular_acceleration: RsFrame::w_dot at camera time t_ns, the
  // rate of change of gyroRate (central difference over +-10 ms, the bias cancels). Zero otherwise or
  // without IMU samples over that span.
  Vec3 readoutWDot(int64_t t_ns) const;

  // The window term: after the initialisation, and before it with the gyroscope's rotations on.
  const WindowTerm* term() const { return initialised_ || termsBeforeInit() ? term_.get() : nullptr; }
  bool gyroBeforeInit() const { return o_.gyro_bias_sigma_before_init_rad_s > 0.0; }
  bool twistBeforeInit() const { return rolling_ && o_.twist_gyro_sigma_before_init_rad_s > 0.0; }
  bool termsBeforeInit() const { return gyroBeforeInit() || twistBeforeInit(); }
  // The offset is estimated and searched before the initialisation (init_time_offset_search_ms).
  bool searchesOffset() const { return o_.estimate_time_offset && o_.init_time_offset_search_ms > 0.0; }
  const InertialTerm* inertialTerm() const { return term_.get(); }
  GlobalStates& globals() { return globals_; }
  const GlobalStates& globals() const { return globals_; }
  double scale() const { return globals_.state.T_wm_wf.scale(); }
  double timeOffset() const { return globals_.state.time_offset_s; }
  double initialScale() const { return scale_init_; }
  const SE3d& T_cm_i() const { return T_cm_i_; }

 private:
  std::shared_ptr<const ImuFactor> makeFactor(const Keyframe& from, const Keyframe& to) const;
  void linkTwistEnergy(Keyframe& kf) const;
  // Before the initialisation, after the offset moved: the window keyframes' twist energies read the
  // gyroscope at the new offset, and their gyroscope factors (gyroBeforeInit) are integrated again.
  void relinkBeforeInit(KeyframeList& window) const;
  int64_t offsetNs() const;

  InertialOptions o_;
  SensorSetup sensors_;
  bool rolling_ = false;
  double twist_sigma_t_ = 0.0, twist_sigma_r_ = 0.0;
  SE3d T_cm_i_;
  ImuBuffer buffer_;
  GlobalStates& globals_;
  std::unique_ptr<InertialTerm> term_;
  bool initialised_ = false;
  double scale_init_ = 1.0;
  int64_t init_t_ns_ = 0;
  // The window's mean IMU energy per factor after each optimisation from fail_grace_s on (keyframe time,
  // value): the run's level, the stretch of high energy, the warning at the end.
  std::vector<std::pair<int64_t, double>> energies_;
  double energy_level_ = -1.0;       // median over the first fail_sustained_s of energies_ (-1: not yet)
  int64_t high_chi2_since_ns_ = -1;  // first keyframe time of the current stretch of high energy (-1: none)
  std::string status_ = "waiting for keyframes";
  int refusals_ = 0;
  std::string first_refusal_;
  int64_t first_refusal_t_ns_ = 0;
  void noteRefusal(int64_t t_ns);  // status_ holds the reason
};

}  // namespace rsvio
