// Camera-body extrinsic for evaluating camera-frame trajectories against body-frame ground truth.
//
// EuRoC's mav0/cam0/sensor.yaml holds T_BS (p_B = T_BS * p_C, conventions.md "Frames"). The framework
// does not link yaml-cpp, so this is a deliberately minimal text reader: it finds the line "T_BS:" and
// reads the 16 numbers of the following "data: [ ... ]" list (which may span lines), row-major. It
// checks the last row is 0 0 0 1 and the rotation is orthonormal to 1e-3, then projects it onto SO(3)
// (the files print about 12 digits). Anything else in the file is ignored.
//
// Mapping ground truth: T_W_C = T_W_B * T_B_C with T_B_C = T_BS, i.e. p_W_C = p_W_B + R_W_B * t_BS and
// q_W_C = q_W_B * q_BS. A trajectory of camera poses is compared with these.
#pragma once
#include <Eigen/Geometry>
#include <string>

#include "rsvio/io/trajectory.h"

namespace rsvio::eval {

// Throws DataError "path:line: ..." when T_BS is missing or malformed.
Eigen::Isometry3d readSensorYamlTBS(const std::string& sensor_yaml_path);

// Returns T_W_C for every T_W_B pose; frame becomes kCamera.
io::Trajectory mapBodyToCamera(const io::Trajectory& body_traj, const Eigen::Isometry3d& T_B_C);

}  // namespace rsvio::eval
