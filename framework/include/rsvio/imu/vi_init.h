// Visual-inertial initialisation: metric scale, gravity direction, velocities and gyroscope bias from
// keyframe poses known up to scale (T_Cf_Wf) and the IMU (paper Fig. 3: it yields the first T_Wm_Wf).
//
// Contract
// - Input keyframes in time order with camera timestamps (middle row) and poses T_Cf_Wf in any
//   free-scale, arbitrarily oriented world W_f; the IMU buffer on the IMU clock (t_imu = t_cam +
//   time_offset_s); calibrated T_Cm_I = T_C_B.
// - Steps (docs/imu.md, "Initialisation"), as in VINS-Mono / ORB-SLAM3:
//   1. gyroscope bias from the rotations alone (Gauss-Newton on log(dR(b_g)^T R_i^T R_j)), then
//      re-preintegration at that bias;
//   2. an observability check that refuses to guess: enough keyframes and time, accelerometer
//      excitation (spread of the mean accelerations between keyframes), and the conditioning of
//   3. the linear system in (velocities, gravity in W_f, scale) from eqs. 14-15, weighted by the
//      preintegrated covariances, followed by gravity refinement on the sphere |g| = 9.81;
//   4. optionally a non-linear refinement of (scale, gravity direction, velocities, b_g, b_a) on the
//      full IMU factors (visual_inertial_factor.h) with poses fixed, b_a under a zero-mean prior.
// - Output: T_Wm_Wf = (s, R_g) with R_g the smallest rotation taking W_f's gravity direction to -z
//   (yaw about gravity is unobservable and left as in W_f), velocities in W_m, biases. When the data
//   do not determine these, success = false and `status` says why with the measured figure and the
//   threshold it failed (for the log and report.json), e.g.
//   "waiting for excitation: accelerometer excitation 0.004 m/s^2 < min_accel_excitation_m_s2 0.25".
#pragma once
#include <string>
#include <vector>

#include "rsvio/imu/imu_buffer.h"
#include "rsvio/imu/imu_types.h"
#include "rsvio/lie/rxso3.h"
#include "rsvio/lie/se3.h"

namespace rsvio {

struct ViInitOptions {
  int min_keyframes = 6;
  double min_duration_s = 1.5;
  // Standard deviation of the mean acceleration (v_j - v_i)/dt_ij over the intervals, m/s^2. VINS-Mono
  // uses the same figure with 0.25; at constant velocity (or at rest) scale and gravity are not
  // separable from the accelerometer bias.
  double min_accel_excitation_m_s2 = 0.25;
  // Smallest over largest singular value of the column-normalised, whitened linear system.
  double min_relative_singular_value = 1e-4;
  // The unconstrained linear estimate of |g| must lie within this fraction of 9.81.
  double max_gravity_norm_error = 0.1;
  int gyro_bias_iterations = 3;
  int gravity_refinement_iterations = 4;
  bool refine_nonlinear = true;
  int nonlinear_iterations = 8;
  double accel_bias_prior_sigma_m_s2 = 0.1;  // zero-mean prior on b_a in the refinement
  ImuBias initial_bias;                      // preintegration starts from it
  // > 0: solve on a subset of the keyframes at least this far apart in time (picked back from the
  // newest), the others' velocities propagated by the IMU from the nearest one picked. The linear
  // system compares accelerations, i.e. second differences of the keyframe positions over the
  // interval: pose noise enters them divided by dt^2 and, being in the regressor, biases the scale
  // low (errors in variables). Rolling-shutter keyframe poses are noisy enough for that to matter
  // (docs/vio.md); 0: every keyframe (consecutive intervals).
  double min_interval_s = 0.0;
  int min_subset_keyframes = 4;  // with min_interval_s > 0: fewer picked keyframes wait for data
};

struct ViInitKeyframe {
  int64_t t_ns = 0;  // camera clock, middle row
  SE3d T_cf_wf;
};

struct ViInitResult {
  bool success = false;
  std::string status;
  RxSO3d T_wm_wf;
  std::vector<Vec3> velocities_wm;  // per keyframe
  ImuBias bias;
  // What the checks measured (reported whether or not they passed).
  double duration_s = 0.0;
  double accel_excitation_m_s2 = 0.0;
  double relative_singular_value = 0.0;
  double gravity_norm_linear_m_s2 = 0.0;
  // Whitened IMU factor energy of the result per interval (mean and largest; poses held, one bias).
  double imu_chi2_mean = 0.0;
  double imu_chi2_max = 0.0;
};

// The camera-IMU time offset (t_imu = t_cam + offset) that best explains the keyframes' relative
// rotations by the gyroscope: for each candidate offset the gyroscope is preintegrated between
// consecutive keyframes, the gyro bias fitted to the rotations (the initialisation's step 1), and the
// summed squared rotation residual |Log(dR_imu^T R_ij)|^2 taken; candidates on a grid over
// [offset0 - range_s, offset0 + range_s] at range_s / 5, then around the best at a fifth of that
// step twice more, and a parabola through the best and its neighbours. Only changes of the rotation
// rate make the offset visible (at a constant rate every interval's rotation is the same at any
// offset): *cost_curvature (if given) is the parabola's second derivative in rad^2/s^2, small when
// the motion does not show the offset. Returns offset0 when the IMU does not cover the keyframes at
// some candidate. Keyframe times on the camera clock (middle row), poses T_cf_wf.
double estimateTimeOffset(const std::vector<ViInitKeyframe>& keyframes, const ImuBuffer& imu, const ImuNoise& noise,
                          const SE3d& T_cm_i, double offset0, double range_s, const ImuBias& bias0 = ImuBias(),
                          int gyro_bias_iterations = 3, double* cost_curvature = nullptr);

ViInitResult initializeVisualInertial(const std::vector<ViInitKeyframe>& keyframes, const ImuBuffer& imu,
                                      const ImuNoise& noise, const SE3d& T_cm_i, double time_offset_s = 0.0,
                                      const ViInitOptions& options = ViInitOptions());

}  // namespace rsvio
