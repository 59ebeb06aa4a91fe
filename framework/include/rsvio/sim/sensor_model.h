// What the simulated sensors are: the state the simulator hands to effect plugins.
//
// Contract
// - Frames: camera x right, y down, z forward; body = IMU frame; camera.T_B_C maps camera points into
//   the body frame (EuRoC's T_BS). World z up, gravity (0, 0, -9.81) m/s^2.
// - Time (conventions.md): the simulator's clock is the IMU clock; ground truth is on it too, in seconds
//   from the start of the sequence (`t_s`) inside and int64 ns in files. An image is stamped on the
//   CAMERA clock with the capture time of raw row y0 = (h - 1) / 2. With a camera-IMU time offset
//   (Kalibr's sign, t_imu = t_cam + time_offset_s) the image stamped t_cam shows the world at IMU time
//   t_cam + time_offset_s. Row r of that image is read at
//       t_cam + time_offset_s + (r - y0) * line_delay_s     (top_down; (y0 - r) for bottom_up)
//   and, with motion blur, integrates over that row time +- exposure_s / 2.
// - Image values handed to SimEffect::processImage are the linear sensor signal in CV_32F, scaled so
//   that 1.0 is the full-scale (saturation) value; after all effects the simulator clips to [0, 1] and
//   quantises to `bit_depth` bits.
// - `camera` holds only what a calibration would know (it is what sensor.yaml gets): geometry,
//   distortion, extrinsic, rate. The hidden truth (line delay, readout, time offset, exposure) lives in
//   the separate members below and reaches only truth.json.
#pragma once
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "rsvio/core/types.h"

namespace rsvio {

struct SimSensorModel {
  CameraCalibration camera;          // calibration-visible part (line_delay_s/time_offset_s stay 0 here)
  double line_delay_s = 0.0;         // true rolling-shutter line delay (0 = global shutter)
  std::string readout = "top_down";  // "top_down" or "bottom_up"
  double time_offset_s = 0.0;        // true t_imu - t_cam
  double exposure_s = 0.0;           // motion-blur window per row (0 = instantaneous)
  int blur_samples = 1;              // time samples across the exposure window
  int bit_depth = 8;                 // 8 or 16
  ImuNoise imu;                      // IMU noise spec as the datasheet/calibration states it (sensor.yaml)
  double duration_s = 0.0;           // length of the IMU / ground-truth stream
  int64_t start_ns = 0;              // stamp of t_s = 0

  double rowZero() const { return 0.5 * (camera.height - 1); }
  // Capture time of raw row r relative to the image's row-y0 time, in seconds.
  double rowTime(double r) const {
    const double d = r - rowZero();
    return (readout == "bottom_up" ? -d : d) * line_delay_s;
  }
  double readoutTime() const { return line_delay_s * (camera.height - 1); }
};

// Per-image context of SimEffect::processImage.
struct SimImageContext {
  int64_t index = 0;            // frame number in the sequence
  int64_t t_cam_ns = 0;         // the stamp written to cam0/data.csv (camera clock, row y0)
  double t_capture_s = 0.0;     // row-y0 capture time on the IMU clock, s from the start
  const SimSensorModel* sensor = nullptr;
  // Per-frame truth an effect wants in truth.json (e.g. the exposure gain), written as
  // (*frame_truth)["<key>"] = value; one object per frame and effect, never shared between threads.
  nlohmann::json* frame_truth = nullptr;
};

// Context of SimEffect::processImu: the whole IMU stream at once.
struct SimImuContext {
  double rate_hz = 200.0;
  const SimSensorModel* sensor = nullptr;
  // True biases per sample (the ground truth's b_w, b_a). Effects that bias the IMU add to these
  // exactly what they add to the samples, so ground truth and measurements agree.
  std::vector<Vec3> gyro_bias_rad_s;
  std::vector<Vec3> accel_bias_m_s2;
};

}  // namespace rsvio
