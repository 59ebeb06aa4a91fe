// IMU measurements and ground truth from the analytic trajectory.
//
// Contract
// - Times: sample k is at t_k = k / rate_hz seconds from the start, stamped start_ns + round(t_k * 1e9)
//   on the IMU clock; each value is evaluated at exactly the time its stamp says.
// - Gyroscope: omega_B (body angular velocity). Accelerometer: specific force R_W_B^T (a_W - g),
//   g = (0, 0, -9.81) m/s^2, so a body at rest reads +9.81 along its world-up axis. Both come from the
//   trajectory's analytic derivatives, never from differenced poses. Noise and biases are added by
//   effects (effect.imu_noise, effect.imu_bias), which also fill the bias tracks of the ground truth.
#pragma once
#include <cstdint>
#include <vector>

#include "rsvio/core/types.h"
#include "rsvio/sim/trajectory.h"

namespace rsvio::sim {

constexpr double kGravity = 9.81;

struct GroundTruthState {
  int64_t t_ns = 0;
  Vec3 p_W_B = Vec3::Zero();
  Eigen::Quaterniond q_W_B = Eigen::Quaterniond::Identity();
  Vec3 v_W = Vec3::Zero();
  Vec3 gyro_bias = Vec3::Zero();
  Vec3 accel_bias = Vec3::Zero();
};

// Stamps of a stream at rate_hz covering [0, duration_s] (both ends included when on the grid).
std::vector<int64_t> streamStamps(int64_t start_ns, double duration_s, double rate_hz);

// Noise-free IMU samples at the given stamps.
std::vector<ImuSample> idealImu(const SimTrajectory& trajectory, const std::vector<int64_t>& stamps, int64_t start_ns);
ImuSample idealImuAt(const SimTrajectory& trajectory, double t_s);

// Ground-truth states at the given stamps (biases zero; the simulator fills them).
std::vector<GroundTruthState> groundTruth(const SimTrajectory& trajectory, const std::vector<int64_t>& stamps,
                                          int64_t start_ns);

}  // namespace rsvio::sim
