// states.csv: one row per keyframe after its last optimisation (user-contract.md).
//   # t_ns,v_x,v_y,v_z,bg_x,bg_y,bg_z,ba_x,ba_y,ba_z,xi_tx,xi_ty,xi_tz,xi_rx,xi_ry,xi_rz,scale,time_offset_ms,
//     line_delay_us
// v: IMU velocity in the metric world [m/s] (0 without an IMU); bg [rad/s], ba [m/s^2]: biases;
// xi: the keyframe's camera twist per second (translation; rotation), translation in W_f units per s;
// scale: metres per W_f unit when the keyframe was last optimised (the estimate over time; 1 without an
// IMU, 0 before the visual-inertial initialisation);
// time_offset_ms: the camera-IMU time offset (t_imu = t_cam + offset) when the keyframe was last
// optimised, so an online estimate shows over time (the assumed value when it is not estimated);
// line_delay_us: the rolling shutter's line delay [us per row] in the same way (0 for a global shutter).
// readStates also reads the 17- and 18-column files written before the offset and line-delay columns.
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

namespace rsvio {

struct StateRow {
  int64_t t_ns = 0;
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  Eigen::Vector3d bg = Eigen::Vector3d::Zero();
  Eigen::Vector3d ba = Eigen::Vector3d::Zero();
  Eigen::Matrix<double, 6, 1> twist = Eigen::Matrix<double, 6, 1>::Zero();
  double scale = 1.0;
  double time_offset_ms = 0.0;
  double line_delay_us = 0.0;
};

void writeStates(const std::vector<StateRow>& rows, const std::string& path);
std::vector<StateRow> readStates(const std::string& path);  // throws DataError "path:line: ..."

}  // namespace rsvio
