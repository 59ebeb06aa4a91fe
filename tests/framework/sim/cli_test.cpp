// `rsvio simulate` end to end: the EuRoC/ASL files, their headers and calibration, truth.json, 16-bit
// images, the same bytes for any thread count, and a one-line error for a bad config.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

namespace fs = std::filesystem;

namespace {

std::string bin() {
  const char* b = std::getenv("RSVIO_BIN");
  return b ? b : std::string(RSVIO_BINARY_DIR) + "/bin/rsvio";
}

std::string config(const std::string& name) { return std::string(RSVIO_SOURCE_DIR) + "/configs/sim/" + name + ".json"; }

int run(const std::string& args, const std::string& log) {
  return std::system((bin() + " -q simulate " + args + " > " + log + " 2>&1").c_str());
}

std::vector<std::string> lines(const fs::path& p) {
  std::ifstream in(p);
  std::vector<std::string> out;
  for (std::string l; std::getline(in, l);) out.push_back(l);
  return out;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

class SimulateCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("rsvio_sim_cli_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(SimulateCli, WritesTheEurocLayoutAndTruth) {
  const fs::path out = dir_ / "rs";
  ASSERT_EQ(run("--config " + config("tiny_rs") + " --out " + out.string() +
                    " --seed 4 --set motion.duration_s=1 --set 'effects.offset={\"plugin\":\"effect.time_offset\"}'",
                (dir_ / "log").string()),
            0)
      << slurp(dir_ / "log");
  const fs::path mav = out / "mav0";
  const auto cam = lines(mav / "cam0" / "data.csv");
  ASSERT_GE(cam.size(), 10u);
  EXPECT_EQ(cam[0], "#timestamp [ns],filename");
  for (size_t i = 1; i < cam.size(); ++i) {
    const std::string stamp = cam[i].substr(0, cam[i].find(','));
    EXPECT_EQ(cam[i], stamp + "," + stamp + ".png");
    const cv::Mat img = cv::imread((mav / "cam0" / "data" / (stamp + ".png")).string(), cv::IMREAD_UNCHANGED);
    ASSERT_FALSE(img.empty()) << stamp;
    EXPECT_EQ(img.type(), CV_8UC1);
    EXPECT_EQ(img.cols, 320);
    EXPECT_EQ(img.rows, 256);
  }
  const auto imu = lines(mav / "imu0" / "data.csv");
  EXPECT_EQ(imu[0], "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],a_RS_S_x [m s^-2],"
                    "a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]");
  EXPECT_EQ(imu.size(), 1u + 201u);
  const auto gt = lines(mav / "state_groundtruth_estimate0" / "data.csv");
  EXPECT_EQ(gt.size(), imu.size());
  EXPECT_EQ(std::count(gt[1].begin(), gt[1].end(), ','), 16);
  const auto mocap = lines(mav / "mocap0" / "data.csv");
  EXPECT_EQ(mocap.size(), 1u + 121u);
  EXPECT_EQ(std::count(mocap[1].begin(), mocap[1].end(), ','), 7);

  // Calibration files: only what a calibration knows.
  const std::string cam_yaml = slurp(mav / "cam0" / "sensor.yaml"), imu_yaml = slurp(mav / "imu0" / "sensor.yaml");
  for (const char* key : {"T_BS:", "data: [", "rate_hz: 20", "resolution: [320, 256]", "camera_model: pinhole",
                          "intrinsics: [208, 208, 159.5, 127.5]", "distortion_model: radial-tangential", "distortion_coefficients:"})
    EXPECT_NE(cam_yaml.find(key), std::string::npos) << key << "\n" << cam_yaml;
  for (const char* hidden : {"line", "delay", "offset", "readout", "shutter", "exposure"}) EXPECT_EQ(cam_yaml.find(hidden), std::string::npos) << hidden;
  for (const char* key : {"gyroscope_noise_density:", "gyroscope_random_walk:", "accelerometer_noise_density:",
                          "accelerometer_random_walk:", "rate_hz: 200", "T_BS:"})
    EXPECT_NE(imu_yaml.find(key), std::string::npos) << key;

  const nlohmann::json truth = nlohmann::json::parse(slurp(out / "truth.json"));
  EXPECT_EQ(truth.at("seed"), 4);
  EXPECT_NEAR(truth.at("camera").at("line_delay_s").get<double>(), 117.88e-6, 1e-12);
  EXPECT_NEAR(truth.at("clocks").at("time_offset_s").get<double>(), 0.005, 1e-12);
  EXPECT_GT(truth.at("trajectory").at("path_length_m").get<double>(), 0.3);
  EXPECT_GT(truth.at("trajectory").at("mean_rot_speed_deg_s").get<double>(), 10.0);
  EXPECT_EQ(truth.at("frames").size(), cam.size() - 1);
  const auto& f0 = truth.at("frames")[0];
  EXPECT_EQ(f0.at("t_capture_imu_ns").get<int64_t>() - f0.at("t_ns").get<int64_t>(), 5000000);
  EXPECT_EQ(std::to_string(f0.at("t_ns").get<int64_t>()), cam[1].substr(0, cam[1].find(',')));
  bool has_rs = false;
  for (const auto& e : truth.at("effects")) has_rs = has_rs || e.at("plugin") == "effect.rolling_shutter";
  EXPECT_TRUE(has_rs);
}

TEST_F(SimulateCli, SameBytesForAnyThreadCountAnd16Bit) {
  const std::string common = " --config " + config("tiny_rs") + " --set motion.duration_s=0.6 --set camera.bit_depth=16";
  ASSERT_EQ(run(common + " --threads 1 --out " + (dir_ / "a").string(), (dir_ / "log").string()), 0) << slurp(dir_ / "log");
  ASSERT_EQ(run(common + " --threads 2 --out " + (dir_ / "b").string(), (dir_ / "log").string()), 0) << slurp(dir_ / "log");
  size_t files = 0;
  for (const auto& entry : fs::recursive_directory_iterator(dir_ / "a")) {
    if (!entry.is_regular_file() || entry.path().filename() == "truth.json") continue;
    const fs::path other = dir_ / "b" / fs::relative(entry.path(), dir_ / "a");
    ASSERT_TRUE(fs::exists(other)) << other;
    EXPECT_EQ(slurp(entry.path()), slurp(other)) << entry.path();
    ++files;
    if (entry.path().extension() == ".png")
      EXPECT_EQ(cv::imread(entry.path().string(), cv::IMREAD_UNCHANGED).type(), CV_16UC1);
  }
  EXPECT_GT(files, 10u);
}

TEST_F(SimulateCli, BadConfigIsAOneLineErrorWithThePath) {
  const int rc = run("--config " + config("tiny_gs") + " --out " + (dir_ / "x").string() + " --set camera.fx=3",
                     (dir_ / "log").string());
  EXPECT_NE(rc, 0);
  const std::string log = slurp(dir_ / "log");
  EXPECT_NE(log.find("camera.fx"), std::string::npos) << log;
  EXPECT_NE(log.find("fx_px"), std::string::npos) << log;
  EXPECT_FALSE(fs::exists(dir_ / "x" / "mav0"));
}

}  // namespace
