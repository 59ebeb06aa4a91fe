// EuRoC/ASL files of a simulated sequence (rsvio/sim/euroc_writer.h).
#include "rsvio/sim/euroc_writer.h"

#include <cstdio>
#include <fstream>
#include <memory>

#include "rsvio/core/error.h"

namespace rsvio::sim {

namespace {

struct File {
  explicit File(const std::string& path) : path_(path), f_(std::fopen(path.c_str(), "w")) {
    if (!f_) throw Error(path + ": cannot write");
  }
  ~File() {
    if (f_) std::fclose(f_);
  }
  void close() {
    const bool bad = std::ferror(f_) != 0;
    if (std::fclose(f_) != 0 || bad) {
      f_ = nullptr;
      throw Error(path_ + ": write failed");
    }
    f_ = nullptr;
  }
  std::FILE* get() { return f_; }
  std::string path_;
  std::FILE* f_;
};

void writeMatrixRows(std::FILE* f, const Eigen::Matrix4d& M) {
  std::fprintf(f, "T_BS:\n  cols: 4\n  rows: 4\n  data: [");
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) std::fprintf(f, "%.15g%s", M(r, c), (r == 3 && c == 3) ? "" : ", ");
    if (r < 3) std::fprintf(f, "\n         ");
  }
  std::fprintf(f, "]\n");
}

}  // namespace

void writeCameraYaml(const std::string& path, const CameraCalibration& c) {
  File f(path);
  std::fprintf(f.get(), "# General sensor definitions.\nsensor_type: camera\ncomment: rsvio simulated camera\n\n");
  std::fprintf(f.get(), "# Sensor extrinsics wrt. the body-frame (camera -> body, p_B = T_BS p_C).\n");
  writeMatrixRows(f.get(), c.T_B_C.matrix());
  std::fprintf(f.get(), "\n# Camera specific definitions.\nrate_hz: %.9g\nresolution: [%d, %d]\ncamera_model: pinhole\n",
               c.rate_hz, c.width, c.height);
  std::fprintf(f.get(), "intrinsics: [%.12g, %.12g, %.12g, %.12g] #fu, fv, cu, cv\n", c.intrinsics[0], c.intrinsics[1],
               c.intrinsics[2], c.intrinsics[3]);
  const bool equi = c.distortion == "equidistant";
  std::fprintf(f.get(), "distortion_model: %s\n", equi ? "equidistant" : "radial-tangential");
  double k[4] = {0, 0, 0, 0};
  for (int i = 0; i < 4 && i < c.distortion_coeffs.size(); ++i) k[i] = c.distortion_coeffs[i];
  std::fprintf(f.get(), "distortion_coefficients: [%.12g, %.12g, %.12g, %.12g]\n", k[0], k[1], k[2], k[3]);
  f.close();
}

void writeImuYaml(const std::string& path, const ImuNoise& n) {
  File f(path);
  std::fprintf(f.get(), "#Default imu sensor yaml file\nsensor_type: imu\ncomment: rsvio simulated IMU\n\n");
  std::fprintf(f.get(), "# Sensor extrinsics wrt. the body-frame.\n");
  writeMatrixRows(f.get(), Eigen::Matrix4d::Identity());
  std::fprintf(f.get(), "rate_hz: %.9g\n\n# inertial sensor noise model parameters (static)\n", n.rate_hz);
  std::fprintf(f.get(), "gyroscope_noise_density: %.6e     # [ rad / s / sqrt(Hz) ]   ( gyro \"white noise\" )\n",
               n.gyro_noise_density);
  std::fprintf(f.get(), "gyroscope_random_walk: %.6e       # [ rad / s^2 / sqrt(Hz) ] ( gyro bias diffusion )\n",
               n.gyro_random_walk);
  std::fprintf(f.get(), "accelerometer_noise_density: %.6e # [ m / s^2 / sqrt(Hz) ]   ( accel \"white noise\" )\n",
               n.accel_noise_density);
  std::fprintf(f.get(), "accelerometer_random_walk: %.6e   # [ m / s^3 / sqrt(Hz) ]   ( accel bias diffusion )\n",
               n.accel_random_walk);
  f.close();
}

void writeImuCsv(const std::string& path, const std::vector<ImuSample>& samples) {
  File f(path);
  std::fprintf(f.get(),
               "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],"
               "a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n");
  for (const ImuSample& s : samples)
    std::fprintf(f.get(), "%lld,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g\n", static_cast<long long>(s.t_ns), s.gyro_rad_s.x(),
                 s.gyro_rad_s.y(), s.gyro_rad_s.z(), s.accel_m_s2.x(), s.accel_m_s2.y(), s.accel_m_s2.z());
  f.close();
}

void writeCameraCsv(const std::string& path, const std::vector<int64_t>& stamps) {
  File f(path);
  std::fprintf(f.get(), "#timestamp [ns],filename\n");
  for (int64_t t : stamps) std::fprintf(f.get(), "%lld,%lld.png\n", static_cast<long long>(t), static_cast<long long>(t));
  f.close();
}

void writeGroundTruthCsv(const std::string& path, const std::vector<GroundTruthState>& states) {
  File f(path);
  std::fprintf(f.get(),
               "#timestamp,p_RS_R_x [m],p_RS_R_y [m],p_RS_R_z [m],q_RS_w [],q_RS_x [],q_RS_y [],q_RS_z [],"
               "v_RS_R_x [m s^-1],v_RS_R_y [m s^-1],v_RS_R_z [m s^-1],"
               "b_w_RS_S_x [rad s^-1],b_w_RS_S_y [rad s^-1],b_w_RS_S_z [rad s^-1],"
               "b_a_RS_S_x [m s^-2],b_a_RS_S_y [m s^-2],b_a_RS_S_z [m s^-2]\n");
  for (const GroundTruthState& s : states) {
    const Eigen::Quaterniond& q = s.q_W_B;
    std::fprintf(f.get(), "%lld,%.12g,%.12g,%.12g,%.15g,%.15g,%.15g,%.15g,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g\n",
                 static_cast<long long>(s.t_ns), s.p_W_B.x(), s.p_W_B.y(), s.p_W_B.z(), q.w(), q.x(), q.y(), q.z(),
                 s.v_W.x(), s.v_W.y(), s.v_W.z(), s.gyro_bias.x(), s.gyro_bias.y(), s.gyro_bias.z(), s.accel_bias.x(),
                 s.accel_bias.y(), s.accel_bias.z());
  }
  f.close();
}

void writeMocapCsv(const std::string& path, const std::vector<GroundTruthState>& states) {
  File f(path);
  std::fprintf(f.get(), "#timestamp [ns],p_RS_R_x [m],p_RS_R_y [m],p_RS_R_z [m],q_RS_w [],q_RS_x [],q_RS_y [],q_RS_z []\n");
  for (const GroundTruthState& s : states) {
    const Eigen::Quaterniond& q = s.q_W_B;
    std::fprintf(f.get(), "%lld,%.12g,%.12g,%.12g,%.15g,%.15g,%.15g,%.15g\n", static_cast<long long>(s.t_ns), s.p_W_B.x(),
                 s.p_W_B.y(), s.p_W_B.z(), q.w(), q.x(), q.y(), q.z());
  }
  f.close();
}

void writeGroundTruthYaml(const std::string& path, const std::string& sensor_type, const std::string& comment) {
  File f(path);
  std::fprintf(f.get(), "sensor_type: %s\ncomment: %s\n\n# Sensor extrinsics wrt. the body-frame.\n", sensor_type.c_str(),
               comment.c_str());
  writeMatrixRows(f.get(), Eigen::Matrix4d::Identity());
  f.close();
}

}  // namespace rsvio::sim
