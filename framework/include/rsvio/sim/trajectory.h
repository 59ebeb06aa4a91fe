// Smooth simulated body (IMU) trajectories with analytic derivatives.
//
// Contract
// - Frames: world z up; the body frame is "camera-like" (x right, y down, z forward) so that the camera,
//   mounted with a small extrinsic T_B_C, looks roughly along body z. Time t_s in seconds from the
//   start of the sequence, on the IMU clock.
// - Position: p(t) = centre + sum of sinusoids per axis, in two bands: a slow "walk around the room"
//   band and a fast "hand-held shake" band. Orientation: R_W_B(t) = Rz(yaw) * M * Rx(pitch) * Rz(roll)
//   with M the level camera looking along world +x, and yaw, pitch, roll sums of sinusoids in the same
//   two bands. Every derivative is analytic: v, a in the world frame; omega_B and alpha_B (the body
//   angular velocity and acceleration, R' = R [omega_B]x) in the body frame. Nothing is differenced.
// - generate() draws the frequencies and phases from the "trajectory" stream and scales the two bands
//   so that the sequence's mean linear/angular speed and acceleration (sampled like the paper's Table I)
//   hit the targets, while the position stays inside the allowed box and pitch/roll inside their limits.
#pragma once
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <random>
#include <string>
#include <vector>

#include "rsvio/core/types.h"

namespace rsvio::sim {

struct MotionSpec {
  double duration_s = 20.0;
  double mean_speed_m_s = 0.9;
  double mean_rot_speed_deg_s = 75.0;
  double mean_accel_m_s2 = 2.2;
  double mean_rot_accel_deg_s2 = 267.0;
  Eigen::Vector3d box_min = Eigen::Vector3d(-3.3, -2.3, 1.0);  // the body stays in this box
  Eigen::Vector3d box_max = Eigen::Vector3d(3.3, 2.3, 2.0);
  double max_pitch_deg = 30.0;
  double max_roll_deg = 15.0;
};

// Full kinematic state of the body at one time.
struct BodyState {
  double t_s = 0.0;
  Eigen::Quaterniond q_W_B = Eigen::Quaterniond::Identity();
  Vec3 p_W_B = Vec3::Zero();
  Vec3 v_W = Vec3::Zero();      // m/s, world
  Vec3 a_W = Vec3::Zero();      // m/s^2, world (kinematic, without gravity)
  Vec3 omega_B = Vec3::Zero();  // rad/s, body
  Vec3 alpha_B = Vec3::Zero();  // rad/s^2, body
  Eigen::Isometry3d T_W_B() const;
};

// Statistics as in the paper's Table I (means over uniformly sampled times).
struct MotionStats {
  double duration_s = 0, path_length_m = 0;
  double mean_speed_m_s = 0, mean_rot_speed_deg_s = 0, mean_accel_m_s2 = 0, mean_rot_accel_deg_s2 = 0;
  double max_speed_m_s = 0, max_rot_speed_deg_s = 0, max_accel_m_s2 = 0, max_rot_accel_deg_s2 = 0;
  Vec3 min_position = Vec3::Zero(), max_position = Vec3::Zero();
  double max_abs_pitch_deg = 0, max_abs_roll_deg = 0;
};

// One sinusoid a * sin(w t + phase) and its derivatives.
struct Wave {
  double amp = 0, w = 0, phase = 0;
};

class SimTrajectory {
 public:
  // Scalar signals: 0..2 position x, y, z; 3 yaw, 4 pitch, 5 roll. Each is base + slow + fast waves.
  static constexpr int kSignals = 6;

  SimTrajectory() = default;
  // Draws and fits a trajectory (see the contract). Throws ConfigError when the targets cannot be met
  // inside the box (the message names the motion keys).
  static SimTrajectory generate(const MotionSpec& spec, std::mt19937_64& rng);

  BodyState state(double t_s) const;
  Eigen::Isometry3d pose(double t_s) const;  // T_W_B
  MotionStats stats(double sample_rate_hz = 200.0) const;
  double duration() const { return duration_s_; }

  // Band scales found by the fit, for truth.json.
  double translationSlowScale() const { return scale_[0]; }
  double translationFastScale() const { return scale_[1]; }
  double rotationSlowScale() const { return scale_[2]; }
  double rotationFastScale() const { return scale_[3]; }

 private:
  // value, first, second derivative of signal i at t.
  void signal(int i, double t, double& f, double& df, double& ddf) const;

  double duration_s_ = 0.0;
  double base_[kSignals] = {0, 0, 0, 0, 0, 0};
  std::vector<Wave> slow_[kSignals];
  std::vector<Wave> fast_[kSignals];
  double scale_[4] = {1, 1, 1, 1};  // slow/fast of translation, slow/fast of rotation
  friend class TrajectoryFitter;
};

}  // namespace rsvio::sim
