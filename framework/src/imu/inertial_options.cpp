// The "imu" section: parameter table and reading (contract in rsvio/imu/inertial_options.h).
#include "rsvio/imu/inertial_options.h"

#include "rsvio/config/validate.h"
#include "rsvio/core/error.h"

namespace rsvio {

ParamTable inertialParamTable() {
  const InertialOptions d;
  return {
      paramBool("enabled", d.enabled,
                "visual-inertial estimation: IMU factors, metric scale and gravity, velocities and biases "
                "(needs a dataset with an IMU)"),
      paramDouble("imu_weight", d.imu_weight, 0.0, 1e6, "", "weight alpha of the IMU factors (paper eq. 34)"),
      paramDouble("twist_weight", d.twist_weight, 0.0, 1e6, "",
                  "weight beta of the twist energy (paper eq. 34; rolling shutter with motion.imu)"),
      paramBool("estimate_time_offset", d.estimate_time_offset,
                "estimate the camera-IMU time offset online (t_imu = t_cam + offset, Kalibr's sign); starts "
                "from the calibration's (plus time_offset_correction_ms)"),
      paramDouble("init_time_offset_search_ms", d.init_time_offset_search_ms, 0.0, 500.0, "ms",
                  "with estimate_time_offset: before the visual-inertial initialisation, at each attempt, the offset "
                  "is searched within +- this of the starting one by the keyframes' rotations against the "
                  "gyroscope, and the online estimate starts there (0: no search; docs/vio.md, Time offset)"),
      paramDouble("time_offset_correction_ms", d.time_offset_correction_ms, -1000.0, 1000.0, "ms",
                  "added to the calibration's camera-IMU time offset (t_imu = t_cam + offset): the value rsvio "
                  "diagnose measures when the calibration lacks it"),
      paramBool("frame_twist_from_imu", d.frame_twist_from_imu,
                "rolling shutter, after the initialisation: a new frame's twist (held by the tracker, used by the "
                "candidate tracer) from the IMU (gyroscope at the frame's time, propagated velocity; paper eq. 32) "
                "instead of from the tracked frames"),
      paramBool("frame_rotation_from_gyro_before_init", d.frame_rotation_from_gyro_before_init,
                "with frame_twist_from_imu, before the initialisation: the frame twist's rotation from the gyroscope "
                "at the frame's time (gyro bias 0), its translation from the tracked frames"),
      paramBool("init_rates_from_gyro", d.init_rates_from_gyro,
                "rolling shutter: the monocular start's rotation rate of each image from the gyroscope at its time "
                "(gyro bias 0) instead of from the corner tracks (backend.init_rotation_rates); not while the time "
                "offset is searched (estimate_time_offset with init_time_offset_search_ms > 0)"),
      paramBool("init_track_guess_from_gyro", d.init_track_guess_from_gyro,
                "the monocular start's corner tracks start each search where the gyroscope's rotation since the "
                "previous frame moves the corner (gyro bias 0), plus the flow the rotation left unexplained in the "
                "corner's previous step, instead of where it was"),
      paramBool("readout_angular_acceleration", d.readout_angular_acceleration,
                "rolling shutter: the rows' rotation to second order in the row time, with the twist rotation's rate of "
                "change from the gyroscope (known, not optimised)"),
      paramDouble("smooth_motion_weight", d.smooth_motion_weight, 0.0, 1e6, "",
                  "rolling shutter: weight of the smooth-motion twist prior of keyframes that have the IMU twist "
                  "energy (after the initialisation); 1: the same as before it"),
      paramDouble("gyro_bias_sigma_before_init_rad_s", d.gyro_bias_sigma_before_init_rad_s, 0.0, 10.0, "rad/s",
                  "before the initialisation: the gyroscope's relative rotations between keyframes in the window, "
                  "with this sigma for the gyro bias not estimated yet; 0: off"),
      paramDouble("twist_gyro_sigma_before_init_rad_s", d.twist_gyro_sigma_before_init_rad_s, 0.0, 10.0, "rad/s",
                  "rolling shutter, before the initialisation: each keyframe's twist rotation held to the gyroscope "
                  "at its time with this sigma (noise and the gyro bias not estimated yet); 0: off"),
      paramDouble("smooth_motion_rot_weight_before_init", d.smooth_motion_rot_weight_before_init, 0.0, 1e6, "",
                  "with twist_gyro_sigma_before_init_rad_s: the weight of the smooth-motion prior's rotation rows on "
                  "keyframes whose twist rotation the gyroscope holds; 1: as without it"),
      paramInt("init_min_keyframes", d.init_min_keyframes, 3, 1000, "",
               "keyframes before the visual-inertial initialisation is tried"),
      paramDouble("init_min_duration_s", d.init_min_duration_s, 0.0, 1e6, "s",
                  "time the initialisation's keyframes must span"),
      paramDouble("init_min_accel_excitation_m_s2", d.init_min_accel_excitation_m_s2, 0.0, 1e3, "m/s^2",
                  "spread of the mean accelerations the initialisation needs (VINS-Mono: 0.25)"),
      paramDouble("init_max_gravity_norm_error", d.init_max_gravity_norm_error, 0.0, 1.0, "",
                  "the linear estimate of |g| must lie within this fraction of 9.81"),
      paramDouble("accel_bias_prior_sigma_m_s2", d.accel_bias_prior_sigma_m_s2, 1e-6, 1e3, "m/s^2",
                  "zero-mean prior on the accelerometer bias in the initialisation"),
      paramDouble("init_max_gyro_bias_rad_s", d.init_max_gyro_bias_rad_s, 0.0, 1e3, "rad/s",
                  "refuse an initialisation whose gyro bias exceeds this (tried again at the next keyframe)"),
      paramDouble("init_max_accel_bias_m_s2", d.init_max_accel_bias_m_s2, 0.0, 1e3, "m/s^2",
                  "refuse an initialisation whose accelerometer bias exceeds this (the keyframe poses do not "
                  "fit the IMU yet; tried again at the next keyframe)"),
      paramDouble("init_min_interval_s", d.init_min_interval_s, 0.0, 1e3, "s",
                  "the initialisation solves on keyframes at least this far apart (picked back from the newest; "
                  "0: every keyframe): noisy keyframe poses bias its scale low over short intervals"),
      paramDouble("init_max_imu_chi2", d.init_max_imu_chi2, 0.0, 1e300, "",
                  "refuse an initialisation whose IMU factors at its solution (poses held) have a mean whitened "
                  "energy above this (the keyframe poses do not fit the IMU; tried again at the next keyframe); "
                  "0: no test"),
      paramInt("init_refusals_warn", d.init_refusals_warn, 0, 1000000, "",
               "warn when the initialisation succeeded only after this many refused attempts (the start's "
               "keyframe poses did not fit the IMU: the trajectory before it may be broken); 0: no warning"),
      paramInt("init_restart_refusals", d.init_restart_refusals, 0, 1000000, "",
               "before the visual-inertial initialisation: start again (window, tracking, monocular start) when "
               "the initialisation was refused this many times in the attempt, or when the attempt failed; "
               "0: off"),
      paramInt("init_max_restarts", d.init_max_restarts, 0, 100, "", "the most restarts of the start in a run"),
      paramDouble("init_restart_within_s", d.init_restart_within_s, 0.0, 1e6, "s",
                  "a start is restarted only within this time of its first frame (its points and "
                  "observation rows are held back until then)"),
      paramBool("dynamic_marginalization", d.dynamic_marginalization,
                "dynamic marginalisation for the scale (VI-DSO): the window switches to a second prior holding "
                "only newer IMU factors and twist energies when the scale leaves the interval around the first's"),
      paramDouble("dynamic_marginalization_interval", d.dynamic_marginalization_interval, 1.0001, 100.0, "",
                  "d of dynamic marginalisation: the priors switch when the scale leaves [s_mid / d, s_mid * d]"),
      paramDouble("init_scale_factor", d.init_scale_factor, 1e-3, 1e3, "",
                  "multiplies the scale the initialisation found (an experiment: start the scale wrong and watch "
                  "it converge; 1 for real runs)"),
      paramDouble("repreintegrate_gyro_bias_rad_s", d.repreintegrate_gyro_bias_rad_s, 0.0, 10.0, "rad/s",
                  "re-preintegrate an IMU factor when the gyro bias moved further from its linearisation"),
      paramDouble("repreintegrate_accel_bias_m_s2", d.repreintegrate_accel_bias_m_s2, 0.0, 100.0, "m/s^2",
                  "re-preintegrate an IMU factor when the accelerometer bias moved further"),
      paramDouble("fail_max_gyro_bias_rad_s", d.fail_max_gyro_bias_rad_s, 0.0, 1e6, "rad/s",
                  "the run fails when a gyro bias estimate exceeds this (bias runaway)"),
      paramDouble("fail_max_accel_bias_m_s2", d.fail_max_accel_bias_m_s2, 0.0, 1e6, "m/s^2",
                  "the run fails when an accelerometer bias estimate exceeds this (bias runaway)"),
      paramDouble("fail_max_scale_change", d.fail_max_scale_change, 1.0, 1e12, "",
                  "the run fails when the scale changes by more than this factor from its initial estimate"),
      paramDouble("fail_max_imu_chi2", d.fail_max_imu_chi2, 0.0, 1e300, "",
                  "the run fails when the mean whitened energy of the window's IMU factors exceeds this "
                  "(exploding IMU residuals; a consistent factor has about 15)"),
      paramDouble("fail_grace_s", d.fail_grace_s, 0.0, 1e6, "s",
                  "the IMU residual test starts this long after the initialisation (the scale settles first)"),
      paramDouble("fail_sustained_imu_chi2", d.fail_sustained_imu_chi2, 0.0, 1e300, "",
                  "the run fails when the window's mean whitened IMU factor energy stays above this and above "
                  "imu.fail_sustained_factor x the run's own level for imu.fail_sustained_s (a window that broke; "
                  "0 = off)"),
      paramDouble("fail_sustained_factor", d.fail_sustained_factor, 1.0, 1e12, "",
                  "times the run's own IMU energy level (its median over the first imu.fail_sustained_s after "
                  "imu.fail_grace_s) that a broken window stays above"),
      paramDouble("fail_sustained_s", d.fail_sustained_s, 0.0, 1e6, "s",
                  "keyframe time over which the run's IMU energy level is taken, and how long it must stay high"),
      paramDouble("warn_imu_chi2", d.warn_imu_chi2, 0.0, 1e300, "",
                  "a warning when the median mean whitened IMU factor energy after imu.fail_grace_s is above "
                  "this (the model does not fit the IMU; 0 = none)"),
  };
}

InertialOptions InertialOptions::fromParams(const Params& p) {
  InertialOptions o;
  o.enabled = p.getBool("enabled");
  o.imu_weight = p.getDouble("imu_weight");
  o.twist_weight = p.getDouble("twist_weight");
  o.estimate_time_offset = p.getBool("estimate_time_offset");
  o.init_time_offset_search_ms = p.getDouble("init_time_offset_search_ms");
  o.time_offset_correction_ms = p.getDouble("time_offset_correction_ms");
  o.frame_twist_from_imu = p.getBool("frame_twist_from_imu");
  o.smooth_motion_weight = p.getDouble("smooth_motion_weight");
  o.gyro_bias_sigma_before_init_rad_s = p.getDouble("gyro_bias_sigma_before_init_rad_s");
  o.frame_rotation_from_gyro_before_init = p.getBool("frame_rotation_from_gyro_before_init");
  o.init_rates_from_gyro = p.getBool("init_rates_from_gyro");
  o.init_track_guess_from_gyro = p.getBool("init_track_guess_from_gyro");
  o.readout_angular_acceleration = p.getBool("readout_angular_acceleration");
  o.twist_gyro_sigma_before_init_rad_s = p.getDouble("twist_gyro_sigma_before_init_rad_s");
  o.smooth_motion_rot_weight_before_init = p.getDouble("smooth_motion_rot_weight_before_init");
  o.init_min_keyframes = static_cast<int>(p.getInt("init_min_keyframes"));
  o.init_min_duration_s = p.getDouble("init_min_duration_s");
  o.init_min_accel_excitation_m_s2 = p.getDouble("init_min_accel_excitation_m_s2");
  o.init_max_gravity_norm_error = p.getDouble("init_max_gravity_norm_error");
  o.accel_bias_prior_sigma_m_s2 = p.getDouble("accel_bias_prior_sigma_m_s2");
  o.init_max_gyro_bias_rad_s = p.getDouble("init_max_gyro_bias_rad_s");
  o.init_max_accel_bias_m_s2 = p.getDouble("init_max_accel_bias_m_s2");
  o.init_min_interval_s = p.getDouble("init_min_interval_s");
  o.init_max_imu_chi2 = p.getDouble("init_max_imu_chi2");
  o.init_refusals_warn = static_cast<int>(p.getInt("init_refusals_warn"));
  o.init_restart_refusals = static_cast<int>(p.getInt("init_restart_refusals"));
  o.init_max_restarts = static_cast<int>(p.getInt("init_max_restarts"));
  o.init_restart_within_s = p.getDouble("init_restart_within_s");
  o.dynamic_marginalization = p.getBool("dynamic_marginalization");
  o.dynamic_marginalization_interval = p.getDouble("dynamic_marginalization_interval");
  o.init_scale_factor = p.getDouble("init_scale_factor");
  o.repreintegrate_gyro_bias_rad_s = p.getDouble("repreintegrate_gyro_bias_rad_s");
  o.repreintegrate_accel_bias_m_s2 = p.getDouble("repreintegrate_accel_bias_m_s2");
  o.fail_max_gyro_bias_rad_s = p.getDouble("fail_max_gyro_bias_rad_s");
  o.fail_max_accel_bias_m_s2 = p.getDouble("fail_max_accel_bias_m_s2");
  o.fail_max_scale_change = p.getDouble("fail_max_scale_change");
  o.fail_max_imu_chi2 = p.getDouble("fail_max_imu_chi2");
  o.fail_grace_s = p.getDouble("fail_grace_s");
  o.fail_sustained_imu_chi2 = p.getDouble("fail_sustained_imu_chi2");
  o.fail_sustained_factor = p.getDouble("fail_sustained_factor");
  o.fail_sustained_s = p.getDouble("fail_sustained_s");
  o.warn_imu_chi2 = p.getDouble("warn_imu_chi2");
  return o;
}

InertialOptions inertialOptionsFromConfig(const nlohmann::json& effective_config) {
  return InertialOptions::fromParams(sectionParams(effective_config, "imu", inertialParamTable()));
}

}  // namespace rsvio
