// Geometric and inertial calibration in YAML (the only yaml-cpp code in rsvio):
// - EuRoC sensor.yaml of a camera (mav0/camN/sensor.yaml) and of the IMU (mav0/imu0/sensor.yaml);
// - Kalibr camchain yaml (camchain.yaml, camchain-imucam-*.yaml, TUM's camchain-calibration-*.yaml) and
//   Kalibr IMU yaml (imu.yaml, TUM-VI's imu_config.yaml; top level or under "imu0").
//
// Frames and conventions (conventions.md): body = IMU frame. EuRoC's T_BS of a camera maps camera points
// into the sensor-rig body frame; with a non-identity IMU T_BS we chain T_B_C = T_BS(imu)^-1 * T_BS(cam)
// so that our body is the IMU. Kalibr's T_cam_imu maps IMU points into the camera: T_B_C is its inverse;
// a camera with only T_cn_cnm1 (Kalibr camera-only chain) is chained from the one before it.
// Kalibr's timeshift_cam_imu has our sign: t_imu = t_cam + shift.
// Intrinsics [fu, fv, cu, cv] in pixels of the raw image, pixel centres at integer coordinates.
// Distortion: "radial-tangential"/"radtan" (k1 k2 p1 p2), "equidistant"/"equi" (k1..k4), "none".
// Line delay, when a file gives one, under one of: line_delay [s] (Kalibr/aslam's lineDelay unit),
// line_delay_s, line_delay_us, line_delay_ns; readout direction under "readout" (top_down|bottom_up).
//
// Errors: DataError "file:line:col: ..." naming the key; yaml-cpp syntax errors keep yaml-cpp's line
// and column (1-based in messages). Missing optional keys (rate, noise densities) become warnings.
#pragma once
#include <optional>
#include <string>
#include <vector>

#include "rsvio/core/types.h"

namespace rsvio::euroc {

// EuRoC camera sensor.yaml. rate_hz_found tells whether the file had rate_hz.
CameraCalibration readEurocCameraYaml(const std::string& path, std::vector<std::string>& warnings,
                                      bool* rate_hz_found = nullptr);

struct ImuCalibration {
  ImuNoise noise;
  Eigen::Isometry3d T_B_S = Eigen::Isometry3d::Identity();  // EuRoC IMU T_BS (identity in EuRoC)
  bool rate_found = false;
};

// IMU noise yaml in either dialect: EuRoC imu0/sensor.yaml (rate_hz, T_BS) or Kalibr's imu.yaml /
// TUM-VI's imu_config.yaml (update_rate; keys at the top level or under "imu0").
ImuCalibration readImuYaml(const std::string& path, std::vector<std::string>& warnings);

// Kalibr camchain: the entry named `camera` ("cam0", "cam1", ...).
CameraCalibration readKalibrCamchain(const std::string& path, const std::string& camera,
                                     std::vector<std::string>& warnings);

// What a calibration file is, judged from its keys: "kalibr" (a top-level "camN" map, Kalibr's chain),
// "euroc" (top-level intrinsics), or "" when neither. Throws DataError on bad YAML.
std::string detectCalibrationFormat(const std::string& path, const std::string& camera);

}  // namespace rsvio::euroc
