// Test fixtures for source.euroc: small datasets in the EuRoC/ASL layout written into a temporary folder
// (64x48 images, a handful of frames, 200 Hz IMU), and loading the plugin exactly as the app does:
// through rsvio::PluginHost on RSVIO_PLUGIN_DIR, params validated by rsvio::validateParams.
#pragma once
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <string>

#include "rsvio/config/validate.h"
#include "rsvio/core/error.h"
#include "rsvio/interfaces/data_source.h"
#include "rsvio/plugin/host.h"

namespace rsvio::test {

namespace fs = std::filesystem;

// A temporary folder removed when the object dies.
class TempDir {
 public:
  TempDir() {
    static int count = 0;
    path_ = fs::temp_directory_path() / ("rsvio_source_" + std::to_string(::getpid()) + "_" + std::to_string(count++));
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  const fs::path& path() const { return path_; }
  std::string str() const { return path_.string(); }

 private:
  fs::path path_;
};

inline void writeText(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream out(p, std::ios::binary);
  out << text;
}

inline std::string readText(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Replaces the first occurrence of `from` in file p (fails the test when absent).
inline void replaceInFile(const fs::path& p, const std::string& from, const std::string& to) {
  std::string s = readText(p);
  const size_t at = s.find(from);
  ASSERT_NE(at, std::string::npos) << "'" << from << "' not in " << p;
  s.replace(at, from.size(), to);
  writeText(p, s);
}

struct DatasetSpec {
  std::string camera = "cam0";
  int width = 64;
  int height = 48;
  int frames = 5;
  int64_t t0_ns = 1000000000000;  // 1000 s
  int64_t frame_dt_ns = 50000000;  // 20 Hz
  bool sixteen_bit = false;
  bool imu = true;
  int64_t imu_dt_ns = 5000000;     // 200 Hz
  int64_t imu_margin_ns = 100000000;  // IMU starts 0.1 s before the first frame, ends 0.1 s after the last
  bool sensor_yaml = true;         // write mav0/<camera>/sensor.yaml (EuRoC calibration)
};

inline int64_t frameStamp(const DatasetSpec& s, int i) { return s.t0_ns + i * s.frame_dt_ns; }

// A recognisable image: a gradient whose values depend on the frame number.
inline cv::Mat testImage(const DatasetSpec& s, int i) {
  cv::Mat img(s.height, s.width, s.sixteen_bit ? CV_16UC1 : CV_8UC1);
  for (int r = 0; r < s.height; ++r)
    for (int c = 0; c < s.width; ++c) {
      const int v = (3 * c + 2 * r + 7 * i) % 256;
      if (s.sixteen_bit)
        img.at<uint16_t>(r, c) = static_cast<uint16_t>(v * 257);
      else
        img.at<uint8_t>(r, c) = static_cast<uint8_t>(v);
    }
  return img;
}

// EuRoC's camera sensor.yaml, in EuRoC's own formatting (T_BS as rows/cols/data).
inline std::string eurocCameraYaml(int width, int height, const std::string& extra = "") {
  return "# General sensor definitions.\n"
         "sensor_type: camera\n"
         "comment: VI-Sensor cam0 (MT9M034)\n"
         "\n"
         "# Sensor extrinsics wrt. the body-frame.\n"
         "T_BS:\n"
         "  cols: 4\n"
         "  rows: 4\n"
         "  data: [0.0148655429818, -0.999880929698, 0.00414029679422, -0.0216401454975,\n"
         "         0.999557249008, 0.0149672133247, 0.025715529948, -0.064676986768,\n"
         "        -0.0257744366974, 0.00375618835797, 0.999660727178, 0.00981073058949,\n"
         "         0.0, 0.0, 0.0, 1.0]\n"
         "\n"
         "# Camera specific definitions.\n"
         "rate_hz: 20\n"
         "resolution: [" + std::to_string(width) + ", " + std::to_string(height) + "]\n"
         "camera_model: pinhole\n"
         "intrinsics: [45.8654, 45.7296, 31.7215, 23.8375] #fu, fv, cu, cv\n"
         "distortion_model: radial-tangential\n"
         "distortion_coefficients: [-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05]\n" + extra;
}

inline std::string eurocImuYaml() {
  return "sensor_type: imu\n"
         "comment: VI-Sensor IMU (ADIS16448)\n"
         "T_BS:\n"
         "  cols: 4\n"
         "  rows: 4\n"
         "  data: [1.0, 0.0, 0.0, 0.0,\n"
         "         0.0, 1.0, 0.0, 0.0,\n"
         "         0.0, 0.0, 1.0, 0.0,\n"
         "         0.0, 0.0, 0.0, 1.0]\n"
         "rate_hz: 200\n"
         "gyroscope_noise_density: 1.6968e-04\n"
         "gyroscope_random_walk: 1.9393e-05\n"
         "accelerometer_noise_density: 2.0000e-3\n"
         "accelerometer_random_walk: 3.0000e-3\n";
}

// Writes a dataset; returns the folder holding mav0/.
inline void writeDataset(const fs::path& dir, const DatasetSpec& s) {
  const fs::path cam = dir / "mav0" / s.camera;
  fs::create_directories(cam / "data");
  std::string csv = "#timestamp [ns],filename\n";
  for (int i = 0; i < s.frames; ++i) {
    const std::string name = std::to_string(frameStamp(s, i)) + ".png";
    csv += std::to_string(frameStamp(s, i)) + "," + name + "\n";
    cv::imwrite((cam / "data" / name).string(), testImage(s, i));
  }
  writeText(cam / "data.csv", csv);
  if (s.sensor_yaml) writeText(cam / "sensor.yaml", eurocCameraYaml(s.width, s.height));
  if (!s.imu) return;
  std::string imu =
      "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],a_RS_S_x [m s^-2],"
      "a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n";
  const int64_t begin = s.t0_ns - s.imu_margin_ns, end = frameStamp(s, s.frames - 1) + s.imu_margin_ns;
  int k = 0;
  for (int64_t t = begin; t <= end; t += s.imu_dt_ns, ++k)
    imu += std::to_string(t) + ",0.01,-0.02," + std::to_string(0.001 * k) + ",0.1,0.2,9.81\n";
  writeText(dir / "mav0" / "imu0" / "data.csv", imu);
  writeText(dir / "mav0" / "imu0" / "sensor.yaml", eurocImuYaml());
}

inline size_t imuSampleCount(const DatasetSpec& s) {
  const int64_t begin = s.t0_ns - s.imu_margin_ns, end = frameStamp(s, s.frames - 1) + s.imu_margin_ns;
  return static_cast<size_t>((end - begin) / s.imu_dt_ns + 1);
}

inline fs::path imuCsv(const fs::path& dir) { return dir / "mav0" / "imu0" / "data.csv"; }
inline fs::path camCsv(const fs::path& dir, const std::string& cam = "cam0") { return dir / "mav0" / cam / "data.csv"; }

// Validated params of source.euroc (the test fails on a validation problem).
inline nlohmann::json validatedParams(PluginHost& host, const nlohmann::json& params) {
  std::vector<ConfigProblem> problems;
  nlohmann::json eff = validateParams(params, host.info("source.euroc").params, "source.params", problems);
  for (const auto& p : problems) ADD_FAILURE() << p.str();
  return eff;
}

// Creates source.euroc through the plugin host, as `rsvio run` does.
inline std::unique_ptr<DataSource> makeSource(const nlohmann::json& params = nlohmann::json::object()) {
  PluginHost host({RSVIO_PLUGIN_DIR});
  const nlohmann::json eff = validatedParams(host, params);
  return host.create<DataSource>("source.euroc", Params(eff, "source"), "source");
}

// Opens a dataset; returns the error message, or "" when open() succeeded.
inline std::string openError(DataSource& src, const fs::path& dir) {
  try {
    src.open(dir.string());
  } catch (const DataError& e) {
    return e.what();
  } catch (const std::exception& e) {
    return std::string("(not a DataError) ") + e.what();
  }
  return "";
}

inline std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const DataError& e) {
    return e.what();
  } catch (const std::exception& e) {
    return std::string("(not a DataError) ") + e.what();
  }
  return "(no error)";
}

inline bool anyContains(const std::vector<std::string>& v, const std::string& needle) {
  for (const auto& s : v)
    if (s.find(needle) != std::string::npos) return true;
  return false;
}

inline std::string joined(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += x + "\n";
  return s;
}

}  // namespace rsvio::test
