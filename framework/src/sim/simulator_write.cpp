// Writing a simulated dataset and its truth.json (rsvio/sim/simulator.h, euroc_writer.h).
#include <atomic>
#include <chrono>
#include <exception>
#include <filesystem>
#include <fstream>
#include <thread>

#include "rsvio/core/error.h"
#include "rsvio/io/image_file.h"
#include "rsvio/sim/euroc_writer.h"
#include "rsvio/sim/simulator.h"

namespace fs = std::filesystem;

namespace rsvio::sim {

namespace {

nlohmann::json matrixRows(const Eigen::Matrix4d& M) {
  nlohmann::json rows = nlohmann::json::array();
  for (int r = 0; r < 4; ++r) rows.push_back({M(r, 0), M(r, 1), M(r, 2), M(r, 3)});
  return rows;
}

nlohmann::json vec(const Vec3& v) { return {v.x(), v.y(), v.z()}; }

void makeDir(const fs::path& p) {
  std::error_code ec;
  fs::create_directories(p, ec);
  if (ec) throw Error(p.string() + ": cannot create directory (" + ec.message() + ")");
}

}  // namespace

nlohmann::json Simulator::truth(const nlohmann::json& frames) const {
  using nlohmann::json;
  const CameraCalibration& c = sensor_.camera;
  const MotionStats st = motionStats();
  json t;
  t["generator"] = std::string("rsvio simulate ") + RSVIO_VERSION;
  t["name"] = settings_.name;
  t["description"] = settings_.description;
  t["seed"] = settings_.seed;
  t["clocks"] = {
      {"imu_and_ground_truth", "imu0, state_groundtruth_estimate0 and mocap0 stamps are on the IMU clock"},
      {"camera", "cam0/data.csv stamps are on the camera clock: the capture time of raw row y0 = (height - 1) / 2"},
      {"time_offset_s", sensor_.time_offset_s},
      {"rule", "t_imu = t_cam + time_offset_s (Kalibr's sign): the image stamped t_cam shows the world at IMU time "
               "t_cam + time_offset_s; row r is read at t_cam + time_offset_s + (r - y0) * line_delay_s (top_down; "
               "(y0 - r) for bottom_up)"},
      {"start_ns", sensor_.start_ns}};
  t["camera"] = {{"width", c.width},
                 {"height", c.height},
                 {"intrinsics_fx_fy_cx_cy", {c.intrinsics[0], c.intrinsics[1], c.intrinsics[2], c.intrinsics[3]}},
                 {"distortion", c.distortion},
                 {"distortion_coeffs", std::vector<double>(c.distortion_coeffs.data(), c.distortion_coeffs.data() + c.distortion_coeffs.size())},
                 {"T_B_C", matrixRows(c.T_B_C.matrix())},
                 {"rate_hz", c.rate_hz},
                 {"shutter", sensor_.line_delay_s > 0 ? "rolling" : "global"},
                 {"line_delay_s", sensor_.line_delay_s},
                 {"readout", sensor_.readout},
                 {"readout_time_s", sensor_.readoutTime()},
                 {"row_zero", sensor_.rowZero()},
                 {"exposure_s", sensor_.exposure_s},
                 {"blur_samples", sensor_.blur_samples},
                 {"bit_depth", sensor_.bit_depth},
                 {"supersampling", settings_.supersampling},
                 {"frames", frame_stamps_.size()}};
  t["imu"] = {{"rate_hz", sensor_.imu.rate_hz},
              {"gyroscope_noise_density", sensor_.imu.gyro_noise_density},
              {"gyroscope_random_walk", sensor_.imu.gyro_random_walk},
              {"accelerometer_noise_density", sensor_.imu.accel_noise_density},
              {"accelerometer_random_walk", sensor_.imu.accel_random_walk},
              {"gravity_m_s2", {0.0, 0.0, -kGravity}},
              {"samples", imu_.size()}};
  json effects = json::array();
  for (const Effect& e : effects_)
    effects.push_back({{"name", e.name},
                       {"plugin", e.plugin},
                       {"order", e.impl->order()},
                       {"in_calibration", e.impl->inCalibration()},
                       {"params", e.params},
                       {"truth", e.impl->truth()}});
  t["effects"] = effects;
  const MotionSpec& ms = settings_.motion;
  t["trajectory"] = {{"duration_s", st.duration_s},
                     {"path_length_m", st.path_length_m},
                     {"mean_speed_m_s", st.mean_speed_m_s},
                     {"mean_rot_speed_deg_s", st.mean_rot_speed_deg_s},
                     {"mean_accel_m_s2", st.mean_accel_m_s2},
                     {"mean_rot_accel_deg_s2", st.mean_rot_accel_deg_s2},
                     {"max_speed_m_s", st.max_speed_m_s},
                     {"max_rot_speed_deg_s", st.max_rot_speed_deg_s},
                     {"max_accel_m_s2", st.max_accel_m_s2},
                     {"max_rot_accel_deg_s2", st.max_rot_accel_deg_s2},
                     {"position_min_m", vec(st.min_position)},
                     {"position_max_m", vec(st.max_position)},
                     {"max_abs_pitch_deg", st.max_abs_pitch_deg},
                     {"max_abs_roll_deg", st.max_abs_roll_deg},
                     {"targets", {{"mean_speed_m_s", ms.mean_speed_m_s},
                                  {"mean_rot_speed_deg_s", ms.mean_rot_speed_deg_s},
                                  {"mean_accel_m_s2", ms.mean_accel_m_s2},
                                  {"mean_rot_accel_deg_s2", ms.mean_rot_accel_deg_s2}}},
                     {"frame", "body (IMU) frame: ground truth gives T_W_B; the camera is T_W_B * T_B_C"},
                     {"statistics", "means over samples at the IMU rate of the analytic |v|, |omega|, |a|, |alpha| "
                                    "(the paper's Table I uses numerical derivatives of ground-truth poses)"}};
  t["scene"] = {{"room_size_m", vec(settings_.scene.room_size_m)},
                {"furniture", settings_.scene.furniture},
                {"table", settings_.scene.table},
                {"texel_mm", settings_.scene.texel_mm}};
  t["files"] = {{"calibration", "mav0/cam0/sensor.yaml and mav0/imu0/sensor.yaml hold only what a calibration would "
                                "know (intrinsics, distortion, T_BS, IMU noise densities); every hidden effect is here only"},
                {"ground_truth", "state_groundtruth_estimate0 at the IMU rate (p, q w-first, v, b_w, b_a); mocap0 at " +
                                     std::to_string(settings_.mocap_rate_hz) + " Hz (p, q)"}};
  t["frames"] = frames;
  t["config"] = config_;
  return t;
}

void Simulator::write(const std::string& dir, const SimProgressFn& progress) {
  const auto t0 = std::chrono::steady_clock::now();
  auto report = [&](const std::string& stage, int64_t done, int64_t total) {
    if (progress)
      progress({stage, done, total, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count()});
  };
  const fs::path root(dir), mav = root / "mav0";
  if (settings_.write_images) {
    report("scene", 0, 1);
    prepareRendering();  // fails early on a bad distortion, before any file is written
    report("scene", 1, 1);
  }
  makeDir(mav / "imu0");
  makeDir(mav / "state_groundtruth_estimate0");
  makeDir(mav / "mocap0");
  report("imu", 0, 1);
  writeImuCsv((mav / "imu0" / "data.csv").string(), imu_);
  writeImuYaml((mav / "imu0" / "sensor.yaml").string(), sensor_.imu);
  writeGroundTruthCsv((mav / "state_groundtruth_estimate0" / "data.csv").string(), ground_truth_);
  writeGroundTruthYaml((mav / "state_groundtruth_estimate0" / "sensor.yaml").string(), "visual-inertial",
                       "rsvio simulated ground truth of the body (IMU) frame");
  writeMocapCsv((mav / "mocap0" / "data.csv").string(), mocap());
  writeGroundTruthYaml((mav / "mocap0" / "sensor.yaml").string(), "mocap",
                       "rsvio simulated motion capture of the body (IMU) frame");
  report("imu", 1, 1);

  nlohmann::json frames = nlohmann::json::array();
  if (settings_.write_images) {
    const fs::path cam = mav / "cam0";
    makeDir(cam / "data");
    const size_t n = frame_stamps_.size();
    std::vector<nlohmann::json> frame_truth(n);
    std::atomic<size_t> next{0}, done{0};
    std::atomic<bool> failed{false};
    std::exception_ptr error;
    std::mutex mutex;
    auto worker = [&] {
      for (size_t i = next++; i < n && !failed; i = next++) {
        try {
          nlohmann::json ft = nlohmann::json::object();
          const cv::Mat img = renderImage(i, &ft);
          const std::string path = (cam / "data" / (std::to_string(frame_stamps_[i]) + ".png")).string();
          io::writePng(path, img, settings_.png_compression);
          frame_truth[i] = std::move(ft);
          const size_t d = ++done;
          std::lock_guard<std::mutex> lock(mutex);
          report("frames", static_cast<int64_t>(d), static_cast<int64_t>(n));
        } catch (...) {
          std::lock_guard<std::mutex> lock(mutex);
          if (!failed) error = std::current_exception();
          failed = true;
        }
      }
    };
    std::vector<std::thread> pool;
    for (int i = 1; i < settings_.threads; ++i) pool.emplace_back(worker);
    worker();
    for (auto& th : pool) th.join();
    if (error) std::rethrow_exception(error);
    writeCameraCsv((cam / "data.csv").string(), frame_stamps_);
    writeCameraYaml((cam / "sensor.yaml").string(), sensor_.camera);
    for (size_t i = 0; i < n; ++i) {
      nlohmann::json f = {{"index", i},
                          {"t_ns", frame_stamps_[i]},
                          {"t_capture_imu_ns", sensor_.start_ns + std::llround(captureTime(i) * 1e9)}};
      if (!frame_truth[i].empty()) f["effects"] = frame_truth[i];
      frames.push_back(std::move(f));
    }
  }
  const std::string truth_path = (root / "truth.json").string();
  std::ofstream out(truth_path);
  if (!out) throw Error(truth_path + ": cannot write");
  out << truth(frames).dump(2) << "\n";
  if (!out) throw Error(truth_path + ": write failed");
  report("done", 1, 1);
}

}  // namespace rsvio::sim
