// Sensor data and calibration types shared by data sources, the simulator and the estimator.
// Frames (conventions.md): world z up, gravity (0,0,-9.81); camera x right, y down, z forward;
// body = IMU frame. T_B_C maps camera points into the body frame (EuRoC's T_BS).
// Time: int64 ns; an image's timestamp is the capture time of its middle raw row y0 = (h-1)/2.
#pragma once
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <limits>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace rsvio {

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;
using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat3 = Eigen::Matrix3d;
using Mat6 = Eigen::Matrix<double, 6, 6>;

// One IMU sample in the body (IMU) frame, time on the IMU clock.
struct ImuSample {
  int64_t t_ns = 0;
  Vec3 gyro_rad_s = Vec3::Zero();     // angular velocity, rad/s
  Vec3 accel_m_s2 = Vec3::Zero();     // specific force, m/s^2 (reads +9.81 on z when level and at rest)
};

// Continuous-time noise densities (Kalibr/EuRoC conventions).
struct ImuNoise {
  double rate_hz = 200.0;
  double gyro_noise_density = 1.7e-4;   // rad/s/sqrt(Hz)
  double gyro_random_walk = 1.9e-5;     // rad/s^2/sqrt(Hz)
  double accel_noise_density = 2.0e-3;  // m/s^2/sqrt(Hz)
  double accel_random_walk = 3.0e-3;    // m/s^3/sqrt(Hz)
};

// Geometric camera calibration of the raw (distorted) image. Pixel centres at integer coordinates.
struct CameraCalibration {
  std::string projection = "pinhole";
  std::string distortion = "none";      // "none", "radtan" (k1 k2 p1 p2), "equidistant" (k1..k4)
  int width = 0;
  int height = 0;
  Eigen::Vector4d intrinsics = Eigen::Vector4d::Zero();  // fx fy cx cy [px]
  Eigen::VectorXd distortion_coeffs;
  Eigen::Isometry3d T_B_C = Eigen::Isometry3d::Identity();  // camera -> body (EuRoC T_BS)
  double rate_hz = 20.0;
  // Only what a calibration would know. A rolling shutter the calibration did not measure is 0 here
  // and must be given in the shutter plugin's params.
  double line_delay_s = 0.0;
  std::string readout = "top_down";     // or "bottom_up"
  double time_offset_s = 0.0;           // t_imu = t_cam + time_offset_s (Kalibr's sign)
  double rowZero() const { return 0.5 * (height - 1); }  // y0 of the raw image
};

// DSO-style photometric calibration, when the dataset ships it (empty members when not).
struct PhotometricCalibration {
  std::vector<float> inverse_response;  // G^-1: raw value -> irradiance, 256 (8 bit) or 65536 entries
  cv::Mat vignette;                     // CV_32F in [0,1], raw image size, empty if none
  std::string response_path;
  std::string vignette_path;
};

struct SensorSetup {
  std::string dataset_dir;
  CameraCalibration camera;
  bool has_imu = false;
  ImuNoise imu;
  PhotometricCalibration photometric;
};

// One image as read from a dataset: raw pixels, no correction applied.
struct Frame {
  int64_t index = 0;           // position in the sequence
  int64_t t_ns = 0;            // capture time of row y0, camera clock
  cv::Mat image;               // CV_8UC1 or CV_16UC1, raw (distorted)
  double exposure_ms = std::numeric_limits<double>::quiet_NaN();  // when the dataset gives it
  std::string path;            // file it came from, for messages
};

}  // namespace rsvio
