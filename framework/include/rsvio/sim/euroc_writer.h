// Writing a simulated sequence in the EuRoC/ASL layout (user-contract.md, "Datasets").
//
//   DIR/mav0/cam0/data.csv                      "#timestamp [ns],filename"; stamps on the camera clock
//   DIR/mav0/cam0/data/<ns>.png                 8- or 16-bit grey, raw (distorted) image
//   DIR/mav0/cam0/sensor.yaml                   T_BS (camera -> body, 4x4 row-major), rate_hz, resolution,
//                                               camera_model pinhole, intrinsics [fu, fv, cu, cv],
//                                               distortion_model radial-tangential | equidistant
//   DIR/mav0/imu0/data.csv                      "#timestamp [ns],w_RS_S_x [rad s^-1],...,a_RS_S_z [m s^-2]"
//   DIR/mav0/imu0/sensor.yaml                   noise densities and random walks, rate_hz, T_BS = I
//   DIR/mav0/state_groundtruth_estimate0/data.csv   p, q (w x y z), v, b_w, b_a of the body at IMU stamps
//   DIR/mav0/mocap0/data.csv                    p, q (w x y z) of the body at the mocap rate
// Only what a calibration would know goes in these files; the hidden truth goes to truth.json.
#pragma once
#include <string>
#include <vector>

#include "rsvio/core/types.h"
#include "rsvio/sim/imu_synth.h"

namespace rsvio::sim {

void writeCameraYaml(const std::string& path, const CameraCalibration& calib);
void writeImuYaml(const std::string& path, const ImuNoise& noise);
void writeImuCsv(const std::string& path, const std::vector<ImuSample>& samples);
void writeCameraCsv(const std::string& path, const std::vector<int64_t>& stamps);
void writeGroundTruthCsv(const std::string& path, const std::vector<GroundTruthState>& states);
void writeMocapCsv(const std::string& path, const std::vector<GroundTruthState>& states);
// sensor.yaml of a ground-truth folder (EuRoC's style: sensor_type and T_BS identity).
void writeGroundTruthYaml(const std::string& path, const std::string& sensor_type, const std::string& comment);

}  // namespace rsvio::sim
