// Schema and settings of simulation configs (rsvio/sim/sim_config.h).
#include "rsvio/sim/sim_config.h"

#include <cmath>
#include <sstream>

#include "rsvio/config/config.h"
#include "rsvio/core/error.h"
#include "rsvio/plugin/host.h"

namespace rsvio::sim {

namespace {
std::string num(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}
}  // namespace

ConfigSchema simConfigSchema() {
  ConfigSchema s;
  s.what = "simulation config";
  s.value("name", paramString("name", "", "name of this simulated sequence"));
  s.value("description", paramString("description", "", "one line on what this sequence is for"));
  s.value("seed", paramInt("seed", 1, 0, 2147483647, "", "seed of every random stream (--seed overrides)"));
  s.value("threads", paramInt("threads", 2, 1, 64, "", "worker threads (the output is identical for any count)"));
  s.section("scene",
            {paramArray("room_size_m", {9.0, 7.0, 3.0}, 3, "m", "room extent x, y, z; the floor is at z = 0"),
             paramInt("furniture", 16, 0, 80, "", "boxes along the walls"),
             paramBool("table", true, "a table in the middle of the room"),
             paramDouble("texel_mm", 4.0, 0.5, 100.0, "mm", "texture resolution (larger is faster to build)"),
             paramDouble("brightness", 1.0, 0.01, 100.0, "", "scales the scene's lighting")},
            "the simulated room");
  s.section("camera",
            {paramInt("width_px", 640, 16, 8192, "px", "image width"),
             paramInt("height_px", 512, 16, 8192, "px", "image height"),
             paramDouble("fx_px", 416.0, 1.0, 1e5, "px", "focal length x"),
             paramDouble("fy_px", 416.0, 1.0, 1e5, "px", "focal length y"),
             paramDouble("cx_px", 319.5, -1e5, 1e5, "px", "principal point x (pixel centres at integers)"),
             paramDouble("cy_px", 255.5, -1e5, 1e5, "px", "principal point y"),
             paramDouble("rate_hz", 20.0, 0.1, 1000.0, "Hz", "frame rate"),
             paramArray("extrinsic_translation_m", {0.045, -0.012, 0.021}, 3, "m",
                        "camera centre in the body (IMU) frame: translation of T_B_C"),
             paramArray("extrinsic_rotation_deg", {1.5, -2.0, 3.0}, 3, "deg",
                        "rotation vector of R_B_C (camera axes in the body frame)"),
             paramInt("supersampling", 2, 1, 8, "", "rays per pixel along each axis (antialiasing)"),
             paramInt("bit_depth", 8, 8, 16, "bit", "PNG bit depth: 8 or 16")},
            "the camera's geometry as a calibration would give it");
  s.section("motion",
            {paramDouble("duration_s", 20.0, 0.5, 3600.0, "s", "length of the sequence"),
             paramDouble("mean_speed_m_s", 0.9, 0.01, 5.0, "m/s", "mean linear speed"),
             paramDouble("mean_rot_speed_deg_s", 75.0, 1.0, 1000.0, "deg/s", "mean angular speed"),
             paramDouble("mean_accel_m_s2", 2.2, 0.01, 50.0, "m/s^2", "mean linear acceleration"),
             paramDouble("mean_rot_accel_deg_s2", 267.0, 1.0, 20000.0, "deg/s^2", "mean angular acceleration"),
             paramDouble("wall_clearance_m", 1.2, 0.2, 50.0, "m", "closest approach of the body to a wall"),
             paramDouble("min_height_m", 1.0, 0.1, 50.0, "m", "lowest body height"),
             paramDouble("max_height_m", 2.0, 0.1, 50.0, "m", "highest body height"),
             paramDouble("max_pitch_deg", 30.0, 0.0, 80.0, "deg", "largest tilt up or down"),
             paramDouble("max_roll_deg", 15.0, 0.0, 80.0, "deg", "largest roll")},
            "the trajectory: targets for its statistics (the paper's Table I) and limits");
  s.section("imu",
            {paramDouble("rate_hz", 200.0, 1.0, 10000.0, "Hz", "IMU sample rate"),
             paramDouble("gyroscope_noise_density", 1.7e-4, 0.0, 1.0, "rad/s/sqrt(Hz)", "gyro white noise (sensor.yaml)"),
             paramDouble("gyroscope_random_walk", 1.9e-5, 0.0, 1.0, "rad/s^2/sqrt(Hz)", "gyro bias random walk (sensor.yaml)"),
             paramDouble("accelerometer_noise_density", 2.0e-3, 0.0, 10.0, "m/s^2/sqrt(Hz)",
                         "accelerometer white noise (sensor.yaml)"),
             paramDouble("accelerometer_random_walk", 3.0e-3, 0.0, 10.0, "m/s^3/sqrt(Hz)",
                         "accelerometer bias random walk (sensor.yaml)")},
            "the IMU's datasheet: what sensor.yaml states; effect.imu_noise generates noise from it");
  s.section("output",
            {paramInt("start_time_ns", 1600000000000000000, 0, 9e18, "ns", "stamp of the first IMU sample"),
             paramDouble("mocap_rate_hz", 120.0, 1.0, 10000.0, "Hz", "rate of mocap0/data.csv"),
             paramDouble("frame_margin_s", 0.1, 0.0, 100.0, "s",
                         "first and last image this far inside the IMU stream"),
             paramInt("png_compression", 1, 0, 9, "", "PNG compression level (0 fastest)"),
             paramBool("write_images", true, "write cam0 images (false: IMU and ground truth only)")},
            "the files written");
  s.multiSlot("effects", PluginKind::Effect, "physical effects, keyed by name (effect.* plugins)");
  return s;
}

nlohmann::json defaultEffects() {
  return {{"image_noise", {{"plugin", "effect.image_noise"}}}, {"imu_noise", {{"plugin", "effect.imu_noise"}}}};
}

nlohmann::json validateSimConfig(nlohmann::json config, PluginHost& host, const std::string& origin,
                                 const std::vector<std::string>& sets) {
  if (config.is_object() && !config.contains("effects")) config["effects"] = defaultEffects();
  nlohmann::json effective = validateConfig(config, simConfigSchema(), host, origin, sets);
  try {
    simSettings(effective);  // cross-field checks
  } catch (const ConfigError& e) {
    throw ConfigError(origin + ": " + e.what());
  }
  return effective;
}

nlohmann::json loadSimConfig(const std::string& path, const std::vector<std::string>& sets,
                             std::optional<int64_t> seed, PluginHost& host) {
  nlohmann::json config = loadConfigWithSets(path, sets);
  if (seed) config["seed"] = *seed;
  return validateSimConfig(std::move(config), host, path, sets);
}

SimSettings simSettings(const nlohmann::json& e) {
  SimSettings s;
  std::vector<std::string> problems;
  s.name = e.value("name", "");
  s.description = e.value("description", "");
  s.seed = e.at("seed").get<uint64_t>();
  s.threads = e.at("threads").get<int>();

  const auto& sc = e.at("scene");
  const auto room = sc.at("room_size_m").get<std::vector<double>>();
  s.scene.room_size_m = Vec3(room[0], room[1], room[2]);
  s.scene.furniture = sc.at("furniture").get<int>();
  s.scene.table = sc.at("table").get<bool>();
  s.scene.texel_mm = sc.at("texel_mm").get<double>();
  s.scene.brightness = sc.at("brightness").get<double>();
  if (s.scene.room_size_m.minCoeff() < 2.0)
    problems.push_back("scene.room_size_m: every extent must be at least 2 m, found " + sc.at("room_size_m").dump());

  const auto& c = e.at("camera");
  CameraCalibration& cal = s.sensor.camera;
  cal.width = c.at("width_px").get<int>();
  cal.height = c.at("height_px").get<int>();
  cal.intrinsics << c.at("fx_px").get<double>(), c.at("fy_px").get<double>(), c.at("cx_px").get<double>(),
      c.at("cy_px").get<double>();
  cal.rate_hz = c.at("rate_hz").get<double>();
  cal.distortion = "none";
  cal.distortion_coeffs = Eigen::VectorXd::Zero(4);
  const auto tr = c.at("extrinsic_translation_m").get<std::vector<double>>();
  const auto rv = c.at("extrinsic_rotation_deg").get<std::vector<double>>();
  const Vec3 rot = Vec3(rv[0], rv[1], rv[2]) * M_PI / 180.0;
  cal.T_B_C = Eigen::Isometry3d::Identity();
  if (rot.norm() > 0) cal.T_B_C.linear() = Eigen::AngleAxisd(rot.norm(), rot.normalized()).toRotationMatrix();
  cal.T_B_C.translation() = Vec3(tr[0], tr[1], tr[2]);
  s.supersampling = c.at("supersampling").get<int>();
  s.sensor.bit_depth = c.at("bit_depth").get<int>();
  if (s.sensor.bit_depth != 8 && s.sensor.bit_depth != 16)
    problems.push_back("camera.bit_depth: expected 8 or 16, found " + c.at("bit_depth").dump());
  if (cal.intrinsics[2] < 0 || cal.intrinsics[2] > cal.width - 1)
    problems.push_back("camera.cx_px: " + num(cal.intrinsics[2]) + " is outside the image [0, " + num(cal.width - 1) + "]");
  if (cal.intrinsics[3] < 0 || cal.intrinsics[3] > cal.height - 1)
    problems.push_back("camera.cy_px: " + num(cal.intrinsics[3]) + " is outside the image [0, " + num(cal.height - 1) + "]");

  const auto& m = e.at("motion");
  MotionSpec& ms = s.motion;
  ms.duration_s = m.at("duration_s").get<double>();
  ms.mean_speed_m_s = m.at("mean_speed_m_s").get<double>();
  ms.mean_rot_speed_deg_s = m.at("mean_rot_speed_deg_s").get<double>();
  ms.mean_accel_m_s2 = m.at("mean_accel_m_s2").get<double>();
  ms.mean_rot_accel_deg_s2 = m.at("mean_rot_accel_deg_s2").get<double>();
  ms.max_pitch_deg = m.at("max_pitch_deg").get<double>();
  ms.max_roll_deg = m.at("max_roll_deg").get<double>();
  const double clear = m.at("wall_clearance_m").get<double>();
  const double z_lo = m.at("min_height_m").get<double>(), z_hi = m.at("max_height_m").get<double>();
  ms.box_min = Vec3(-0.5 * room[0] + clear, -0.5 * room[1] + clear, z_lo);
  ms.box_max = Vec3(0.5 * room[0] - clear, 0.5 * room[1] - clear, z_hi);
  if (ms.box_max.x() - ms.box_min.x() < 0.5 || ms.box_max.y() - ms.box_min.y() < 0.5)
    problems.push_back("motion.wall_clearance_m: " + num(clear) + " m leaves less than 0.5 m to move in a " +
                       num(room[0]) + " x " + num(room[1]) + " m room");
  if (z_hi - z_lo < 0.1)
    problems.push_back("motion.max_height_m: must exceed motion.min_height_m by at least 0.1 m");
  if (z_hi > room[2] - 0.3)
    problems.push_back("motion.max_height_m: " + num(z_hi) + " m is closer than 0.3 m to the ceiling at " + num(room[2]) + " m");
  if (z_lo < 0.9 && s.scene.table)
    problems.push_back("motion.min_height_m: " + num(z_lo) + " m would fly through the table (0.74 m plus things on it); "
                       "use at least 0.9 or set scene.table=false");

  const auto& imu = e.at("imu");
  s.sensor.imu.rate_hz = imu.at("rate_hz").get<double>();
  s.sensor.imu.gyro_noise_density = imu.at("gyroscope_noise_density").get<double>();
  s.sensor.imu.gyro_random_walk = imu.at("gyroscope_random_walk").get<double>();
  s.sensor.imu.accel_noise_density = imu.at("accelerometer_noise_density").get<double>();
  s.sensor.imu.accel_random_walk = imu.at("accelerometer_random_walk").get<double>();

  const auto& o = e.at("output");
  s.sensor.start_ns = o.at("start_time_ns").get<int64_t>();
  s.sensor.duration_s = ms.duration_s;
  s.mocap_rate_hz = o.at("mocap_rate_hz").get<double>();
  s.frame_margin_s = o.at("frame_margin_s").get<double>();
  s.png_compression = o.at("png_compression").get<int>();
  s.write_images = o.at("write_images").get<bool>();
  if (ms.duration_s - 2 * s.frame_margin_s < 1.0 / cal.rate_hz)
    problems.push_back("motion.duration_s: " + num(ms.duration_s) + " s leaves no image between the margins (output.frame_margin_s = " +
                       num(s.frame_margin_s) + " s at each end)");

  if (!problems.empty()) {
    std::string msg = problems.size() == 1 ? problems[0] : std::to_string(problems.size()) + " problems in the config";
    if (problems.size() > 1)
      for (const auto& p : problems) msg += "\n  " + p;
    throw ConfigError(msg);
  }
  return s;
}

}  // namespace rsvio::sim
