// states.csv: one row per keyframe after its last optimisation (user-contract.md).
//   # t_ns,v_x,v_y,v_z,bg_x,bg_y,bg_z,ba_x,ba_y,ba_z,xi_tx,xi_ty,xi_tz,xi_rx,xi_ry,xi_rz,scale
// v: IMU velocity in the metric world [m/s] (0 without an IMU); bg [rad/s], ba [m/s^2]: biases;
// xi: the keyframe's camera twist per second (translation; rotation), translation in W_f units per s;
// scale: metres per W_f unit (1 without an IMU).
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
};

void writeStates(const std::vector<StateRow>& rows, const std::string& path);
std::vector<StateRow> readStates(const std::string& path);  // throws DataError "path:line: ..."

}  // namespace rsvio
