// Options of the visual-inertial estimator: the "imu" section of a run config (paper sec. IV; the
// window terms are backend/inertial_term.h, the initialisation imu/vi_init.h). Without "enabled" the
// run is visual odometry and the dataset's IMU is ignored (said so in the run summary).
//
// Weights are eq. 34's alpha (IMU factors) and beta (twist energy, rolling shutter with motion.imu);
// the twist energy's Sigma comes from the motion.imu plugin (MotionPrior::twistEnergySigma).
// inertialParamTable() is the one table that validation, listings and docs use.
#pragma once
#include <nlohmann/json.hpp>

#include "rsvio/core/types.h"
#include "rsvio/plugin/plugin.h"

namespace rsvio {

struct InertialOptions {
  bool enabled = false;                 // visual-inertial estimation
  double imu_weight = 1.0;              // alpha of eq. 34
  double twist_weight = 1.0;            // beta of eq. 34
  bool estimate_time_offset = false;    // camera-IMU time offset online (t_imu = t_cam + offset)
  // With estimate_time_offset: before the initialisation, at each attempt, the offset is searched within
  // +- this (ms) of the starting one by the rotations alone (estimateTimeOffset, vi_init.h); the online
  // estimate starts there.
  double init_time_offset_search_ms = 50.0;
  // Added to the calibration's time offset (what rsvio diagnose measures when the calibration lacks
  // it); with estimate_time_offset the estimate starts there.
  double time_offset_correction_ms = 0.0;
  // Rolling shutter, after the initialisation: a new frame's twist, which the frame tracker holds and
  // the candidate tracer uses, is the IMU's (eq. 32 at the frame's time: the gyroscope there less the
  // gyro bias, the velocity propagated from the newest keyframe) instead of the tracked frames' rate,
  // which lags a changing rotation by half a frame interval. On the paper's Table I motions it lowered
  // rs_vio's median ATE from 58 to 36 mm (docs/vio.md, "The IMU's twist in the tracker").
  bool frame_twist_from_imu = true;
  // With frame_twist_from_imu, before the initialisation: the frame twist's rotation from the gyroscope
  // at the frame's time (eq. 25's rotation, gyro bias 0), its translation as without the IMU. Off by
  // default: alone it did not keep the early losses from happening (same section); rs_vio.json turns it
  // on with twist_gyro_sigma_before_init_rad_s, which does.
  bool frame_rotation_from_gyro_before_init = false;
  // Rolling shutter: the monocular start's rotation rate of each of its two images from the gyroscope
  // at the image's time (gyro bias 0) instead of fitted from the corner tracks
  // (backend.init_rotation_rates, MonoInitializer::setRateSource); the two keyframes start with them.
  // Not while the offset is searched (estimate_time_offset with init_time_offset_search_ms > 0): the
  // offset the gyroscope would be read at is unknown before the first search, which needs the start's
  // keyframes, and rates read at a wrong one bias that search toward it (docs/vio.md, "The offset search
  // no longer reads the gyroscope at the offset it searches").
  bool init_rates_from_gyro = false;
  // The monocular start's corner tracks (either shutter): each corner's Lucas-Kanade search starts
  // where the gyroscope's rotation since the previous frame moves it (gyro bias 0), plus the flow the
  // rotation left unexplained in the corner's previous step, instead of where it was
  // (MonoInitializer::setTrackGuessSource; VINS-Mono predicts its feature tracks with the IMU rotation).
  // Off by default: it keeps the tracks through seq02's 73 deg/s, but the earlier start it allows was
  // better on some runs and worse on others (docs/vio.md, "Gyroscope-rotated corner guesses").
  bool init_track_guess_from_gyro = false;
  // Rolling shutter: the rows' rotation to second order in the row time, with the rate of change of the
  // twist's rotation from the gyroscope (RsFrame::w_dot, geometry/rs_projection.h): each keyframe's and
  // each tracked frame's w_dot = -R_Cm_I d omega / dt at its time (central difference of the gyroscope
  // over +-10 ms; the bias cancels), known and not optimised. The constant twist of eq. 6 alone misses
  // 0.5 |d omega / dt| t^2 at row time t: about 0.4 px at the outer rows of Table I's sequences 9 and 10
  // (docs/vio.md, "The rows' rotation to second order"). Before and after the initialisation.
  bool readout_angular_acceleration = false;
  // Rolling shutter: the weight of the smooth-motion twist prior (backend/smooth_motion_term.h) of a
  // keyframe that has the IMU twist energy (made after the initialisation); 1: as before it. Lighter
  // weights lost track or were less accurate with motion.imu's default Sigma (0.02 rad/s, 0.1 m/s;
  // docs/vio.md, same section); rs_vio.json sets 0 with that Sigma at 0.002 rad/s and 0.02 m/s, so
  // that the twist energy holds the twists as in the paper (docs/vio.md, "The gyroscope holds the
  // twists all through").
  double smooth_motion_weight = 1.0;
  // Before the initialisation: the gyroscope's relative rotation between consecutive keyframes as a
  // window term on their poses (backend/inertial_term.h), with this sigma for the bias that is not
  // estimated yet [rad/s]; 0: off (the default). The rolling-shutter monocular start's world can turn
  // against the gyroscope (0.1-0.3 rad/s over the first 2 s on Table I sequence 6), and the
  // initialisation is refused until those keyframes are out of its span. With 0.005 that run goes from
  // 207 to 6.4 mm, but over the ten Table I sequences the tracking losses move rather than fall, so it
  // stays off (docs/vio.md, "The gyroscope before the initialisation").
  double gyro_bias_sigma_before_init_rad_s = 0.0;
  // Rolling shutter, before the initialisation: each keyframe's twist energy with its rotation rows
  // alone (the gyroscope at the keyframe's time, gyro bias 0: r = -R_Cm_I w_meas - xi_rot), with this
  // sigma [rad/s] for the gyroscope's noise and the bias not estimated yet; the smooth-motion prior's
  // rotation rows on those keyframes weigh smooth_motion_rot_weight_before_init (they keep that weight
  // after the initialisation, where the full twist energy holds their rotation). 0: off.
  double twist_gyro_sigma_before_init_rad_s = 0.0;
  double smooth_motion_rot_weight_before_init = 1.0;
  // Visual-inertial initialisation (vi_init.h), tried at every new keyframe until it succeeds.
  int init_min_keyframes = 8;
  double init_min_duration_s = 1.5;
  double init_min_accel_excitation_m_s2 = 0.25;
  double init_max_gravity_norm_error = 0.1;
  double accel_bias_prior_sigma_m_s2 = 0.1;  // zero-mean prior on b_a in the initialisation's refinement
  // An initialisation whose biases exceed these is refused (the keyframe poses do not fit the IMU yet,
  // e.g. the monocular start's early drift) and tried again at the next keyframe.
  double init_max_gyro_bias_rad_s = 0.05;
  double init_max_accel_bias_m_s2 = 0.5;
  // > 0: the initialisation solves on keyframes at least this far apart (ViInitOptions::min_interval_s).
  double init_min_interval_s = 0.0;
  // > 0: refuse an initialisation whose IMU factors, at its own solution with the keyframe poses held,
  // have a mean whitened energy above this (ViInitResult::imu_chi2_mean): the keyframe poses do not fit
  // the IMU (the rolling-shutter monocular start's distorted first keyframes, docs/vio.md); tried again
  // at the next keyframe. 0: no test.
  double init_max_imu_chi2 = 0.0;
  // A run whose initialisation succeeded only after this many refused attempts (a solution rejected, or
  // refused by one of the three bounds above: InertialState::noteRefusal) ends with a warning: the keyframe poses of its start did not fit the IMU for that long, and the
  // trajectory before the initialisation may be broken (Table I's seq02 seeds 2-3: 40 and 42 refusals,
  // 830 and 231 mm; the demo's default model on its hidden rolling shutter: 23, 0.89 m; 0-11 in 56
  // visual-inertial runs that ended well, docs/vio.md). 0: no warning.
  int init_refusals_warn = 20;
  // Restart of a start that does not fit the IMU (Odometry::Impl::restart; DSO resets its system,
  // VINS-Mono reinitialises): before the visual-inertial initialisation, within init_restart_within_s
  // of the attempt's first frame, the window, tracking and monocular start begin again from the next
  // frame when the initialisation was refused init_restart_refusals times in this attempt, or when the
  // attempt failed (the monocular start found no pair in backend.init_max_frames frames, tracking
  // lost, visual divergence); at most init_max_restarts times per run. The attempt's frames become
  // untracked; its points and observation rows are held back until the attempt can no longer be
  // discarded (RunRecord::setProvisional), so nothing of a discarded attempt is written.
  // init_restart_refusals 0: off (the run fails, or initialises late, as without it).
  int init_restart_refusals = 0;
  int init_max_restarts = 2;
  double init_restart_within_s = 10.0;
  // Dynamic marginalisation for the scale (backend/dynamic_marginalization.h): a second prior with only
  // the scale-dependent terms since the scale entered its current half-interval, switched in when the
  // scale leaves [s_mid / d, s_mid * d]; d = dynamic_marginalization_interval.
  bool dynamic_marginalization = false;
  double dynamic_marginalization_interval = 1.1;
  // Multiplies the scale the initialisation found (1: as found). For experiments: start the scale wrong
  // and watch the window bring it back (docs/vio.md, "Dynamic marginalisation").
  double init_scale_factor = 1.0;
  // Re-preintegrate an IMU factor when the bias moved further than this from its linearisation.
  double repreintegrate_gyro_bias_rad_s = 0.01;
  double repreintegrate_accel_bias_m_s2 = 0.1;
  // Divergence (the run ends "failed" with the reason).
  double fail_max_gyro_bias_rad_s = 0.5;
  double fail_max_accel_bias_m_s2 = 3.0;
  double fail_max_scale_change = 5.0;   // scale vs the initialisation's, either way
  double fail_max_imu_chi2 = 1e5;       // mean whitened IMU factor energy per factor in the window
  double fail_grace_s = 2.0;            // the residual test starts this long after the initialisation
  // A window that broke: the run fails when, after every optimisation over fail_sustained_s of keyframe
  // time, the mean whitened IMU factor energy per factor stayed above max(fail_sustained_imu_chi2,
  // fail_sustained_factor x the run's own level); the level is the median over the first
  // fail_sustained_s after fail_grace_s (the test starts after it). Relative to the run's level so that
  // an effect the model lacks, which holds the energy high from the start (an unmodelled time offset:
  // thousands), is not taken for a break (warn_imu_chi2 says that instead). 0 = off; docs/vio.md
  // "Divergence".
  double fail_sustained_imu_chi2 = 0.0;
  double fail_sustained_factor = 10.0;
  double fail_sustained_s = 1.0;
  // A warning at the end when the median of that energy over the run after fail_grace_s is above this
  // (a consistent factor has about 15): the model does not fit the IMU (0 = no warning).
  double warn_imu_chi2 = 1000.0;

  static InertialOptions fromParams(const Params& p);
  // The camera-IMU time offset a run assumes (t_imu = t_cam + offset) [s]: the calibration's plus
  // time_offset_correction_ms. The one place that sum is made (estimator, IMU feed, probe.time_offset).
  double assumedTimeOffsetS(const CameraCalibration& c) const {
    return c.time_offset_s + 1e-3 * time_offset_correction_ms;
  }
};

ParamTable inertialParamTable();

// Reads the "imu" section of an effective config with defaults filled in; problems throw ConfigError
// naming each key.
InertialOptions inertialOptionsFromConfig(const nlohmann::json& effective_config);

}  // namespace rsvio
