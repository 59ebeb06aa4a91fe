// source.euroc: opening a dataset (contract in euroc_source.h; frame reading in euroc_frames.cpp).
#include "euroc_source.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "calibration_yaml.h"
#include "dataset_index.h"
#include "rsvio/core/error.h"

namespace fs = std::filesystem;

namespace rsvio::euroc {
namespace {

bool isFile(const fs::path& p) {
  std::error_code ec;
  return fs::is_regular_file(p, ec);
}

bool isDir(const fs::path& p) {
  std::error_code ec;
  return fs::is_directory(p, ec);
}

// Names of the camN folders in mav0, for "did you mean" style messages.
std::string listCameras(const fs::path& mav0) {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(mav0, ec))
    if (e.is_directory() && e.path().filename().string().rfind("cam", 0) == 0) names.push_back(e.path().filename());
  std::sort(names.begin(), names.end());
  std::string s;
  for (const auto& n : names) s += (s.empty() ? "" : ", ") + n;
  return s.empty() ? "none" : s;
}

// Kalibr camchains inside the dataset folder, in order of preference.
std::vector<fs::path> kalibrCandidates(const fs::path& dir) {
  std::vector<fs::path> out;
  if (isFile(dir / "dso" / "camchain.yaml")) out.push_back(dir / "dso" / "camchain.yaml");
  for (const fs::path& d : {dir, dir / "dso"}) {
    std::vector<fs::path> found;
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(d, ec)) {
      const std::string n = e.path().filename().string();
      if (e.is_regular_file() && n.find("camchain") != std::string::npos &&
          (e.path().extension() == ".yaml" || e.path().extension() == ".yml") && e.path() != dir / "dso" / "camchain.yaml")
        found.push_back(e.path());
    }
    // Kalibr writes camchain-<bag>.yaml (cameras only) and camchain-imucam-<bag>.yaml (with T_cam_imu and
    // timeshift_cam_imu); TUM names theirs "..._camimu_...". The camera-IMU one is the one to use.
    auto camImu = [](const fs::path& p) {
      const std::string n = p.filename().string();
      return n.find("imucam") != std::string::npos || n.find("camimu") != std::string::npos;
    };
    std::sort(found.begin(), found.end(), [&](const fs::path& a, const fs::path& b) {
      return camImu(a) != camImu(b) ? camImu(a) : a < b;
    });
    out.insert(out.end(), found.begin(), found.end());
  }
  return out;
}

int64_t medianStep(const std::vector<int64_t>& t) {
  if (t.size() < 2) return 0;
  std::vector<int64_t> d;
  d.reserve(t.size() - 1);
  for (size_t i = 1; i < t.size(); ++i) d.push_back(t[i] - t[i - 1]);
  std::nth_element(d.begin(), d.begin() + static_cast<long>(d.size() / 2), d.end());
  return d[d.size() / 2];
}

std::string fmt(const char* f, double v) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), f, v);
  return buf;
}

}  // namespace

int64_t EurocSource::frameTime(size_t i) const {
  if (i >= frames_.size())
    throw Error("source.euroc: frame " + std::to_string(i) + " out of range (" + std::to_string(frames_.size()) +
                " frames)");
  return frames_[i].t_ns;
}

void EurocSource::open(const std::string& dir) {
  sensors_ = SensorSetup();
  frames_.clear();
  imu_.clear();
  imu_loaded_ = false;
  imu_csv_.clear();
  imu_count_ = 0;
  warnings_.clear();
  resolveFolders(dir);
  readCalibration();
  readFrames();
  convertTimestamps();
  readImu();
  if (opt_.photometric == "auto") readPhotometric();
  // Fail at open, not minutes into a run: the first image must decode and match the calibration.
  const cv::Mat first = loadRaw(0);
  if (first.depth() == CV_16U && sensors_.photometric.inverse_response.size() == 256)
    warnings_.push_back(sensors_.photometric.response_path +
                        ": 256 inverse-response values but the images are 16-bit (65536 expected)");
  applyScale();
}

void EurocSource::resolveFolders(const std::string& dir) {
  dir_ = dir;
  if (!isDir(dir)) throw DataError::at(dir, 0, "dataset folder not found");
  const fs::path d(dir);
  if (isDir(d / "mav0")) {
    mav0_ = (d / "mav0").string();
  } else if (isDir(d / opt_.camera) && isFile(d / opt_.camera / "data.csv")) {
    mav0_ = d.string();  // the user pointed at mav0/ itself
  } else {
    std::error_code ec;
    const bool empty = fs::is_empty(d, ec);
    throw DataError::at(dir, 0, std::string(empty ? "folder is empty" : "no mav0/ folder") +
                                    " (expected the EuRoC/ASL layout: mav0/" + opt_.camera + "/data.csv, mav0/" +
                                    opt_.camera + "/data/*.png, mav0/imu0/data.csv)");
  }
  sensors_.dataset_dir = dir;
  cam_dir_ = (fs::path(mav0_) / opt_.camera).string();
  if (!isDir(cam_dir_))
    throw DataError::at(mav0_, 0, "no camera folder '" + opt_.camera + "' (found: " + listCameras(mav0_) +
                                      "; choose one with params.camera)");
  index_path_ = (fs::path(cam_dir_) / "data.csv").string();
  if (!isFile(index_path_)) throw DataError::at(index_path_, 0, "image index not found");
}

void EurocSource::readCalibration() {
  const fs::path d(dir_);
  const fs::path sensor_yaml = fs::path(cam_dir_) / "sensor.yaml";
  std::string path, format;
  if (!opt_.calibration_file.empty()) {
    fs::path p(opt_.calibration_file);
    if (p.is_relative()) p = d / p;
    if (!isFile(p)) throw DataError::at(p.string(), 0, "calibration file not found (params.calibration_file)");
    path = p.string();
    format = opt_.calibration != "auto" ? opt_.calibration : detectCalibrationFormat(path, opt_.camera);
    if (format.empty())
      throw DataError::at(path, 0, "cannot tell a EuRoC sensor.yaml (top-level 'intrinsics') from a Kalibr "
                                   "camchain ('" + opt_.camera + "' map); set params.calibration");
  } else {
    const auto kalibr = kalibrCandidates(d);
    const bool euroc = isFile(sensor_yaml);
    if (opt_.calibration == "kalibr" || (opt_.calibration == "auto" && !kalibr.empty())) {
      if (kalibr.empty())
        throw DataError::at(dir_, 0, "calibration = kalibr but no camchain found (looked for dso/camchain.yaml, "
                                     "camchain*.yaml, dso/*camchain*.yaml; set params.calibration_file)");
      path = kalibr.front().string();
      format = "kalibr";
      if (opt_.calibration == "auto" && euroc)
        warnings_.push_back("using the Kalibr calibration " + path + "; " + sensor_yaml.string() +
                            " is ignored (set params.calibration = \"euroc\" to use it)");
    } else {
      if (!euroc)
        throw DataError::at(sensor_yaml.string(), 0,
                            opt_.calibration == "euroc"
                                ? "calibration file not found"
                                : "no calibration found (looked for this file, dso/camchain.yaml, camchain*.yaml; "
                                  "set params.calibration_file)");
      path = sensor_yaml.string();
      format = "euroc";
    }
  }
  bool rate = false;
  sensors_.camera = format == "kalibr" ? readKalibrCamchain(path, opt_.camera, warnings_)
                                       : readEurocCameraYaml(path, warnings_, &rate);
  rate_known_ = rate;
  calib_path_ = path;
  calib_format_ = format;
  raw_width_ = sensors_.camera.width;
  raw_height_ = sensors_.camera.height;
}

void EurocSource::readFrames() {
  const auto index = readCameraIndex(index_path_, warnings_);
  const fs::path data = fs::path(cam_dir_) / "data";
  frames_.reserve(index.size());
  for (const auto& e : index) {
    FrameEntry f;
    f.stamp_ns = e.stamp_ns;
    f.t_ns = e.stamp_ns;
    f.path = (data / e.file).string();
    f.line = e.line;
    frames_.push_back(std::move(f));
  }
  // Missing files are found now (a cheap stat each) rather than as a failure mid-run.
  for (size_t i = 0; i < frames_.size(); ++i)
    if (!isFile(frames_[i].path))
      throw DataError::at(index_path_, frames_[i].line,
                          "frame " + std::to_string(i) + " at " + std::to_string(frames_[i].stamp_ns) +
                              " ns: image not found: " + frames_[i].path);
  if (!rate_known_) {
    std::vector<int64_t> t;
    for (const auto& f : frames_) t.push_back(f.stamp_ns);
    const int64_t step = medianStep(t);
    if (step > 0) sensors_.camera.rate_hz = 1e9 / static_cast<double>(step);
  }
}

void EurocSource::convertTimestamps() {
  const double calib_ld = sensors_.camera.line_delay_s;
  raw_line_delay_s_ = opt_.line_delay_us > 0 ? opt_.line_delay_us * 1e-6 : calib_ld;
  if (opt_.line_delay_us > 0 && calib_ld > 0 && std::abs(opt_.line_delay_us * 1e-6 - calib_ld) > 0.01 * calib_ld)
    warnings_.push_back("params.line_delay_us = " + fmt("%.4f", opt_.line_delay_us) +
                        " overrides the calibration's line delay of " + fmt("%.4f", calib_ld * 1e6) +
                        " us for the timestamp conversion");
  if (opt_.timestamp_row == "middle") return;
  if (!(raw_line_delay_s_ > 0)) {
    warnings_.push_back("timestamp_row = \"" + opt_.timestamp_row + "\" but the line delay is unknown (0 in " +
                        calib_path_ + "): frame times are left as stamped; converting them to the middle row "
                        "needs params.line_delay_us");
    return;
  }
  const double y0 = 0.5 * (raw_height_ - 1);
  const int64_t shift = static_cast<int64_t>(std::llround(y0 * raw_line_delay_s_ * 1e9));
  const int64_t delta = opt_.timestamp_row == "first" ? shift : -shift;
  for (auto& f : frames_) f.t_ns = f.stamp_ns + delta;
}

void EurocSource::readImu() {
  const fs::path imu_dir = fs::path(mav0_) / "imu0";
  const fs::path csv = imu_dir / "data.csv";
  if (!isFile(csv)) {
    warnings_.push_back(csv.string() + " not found: no IMU data (visual-only runs only)");
    return;
  }
  // One streaming pass checks the whole file (errors and warnings belong to open()); nothing of it is
  // kept but its span and the first steps (the rate): runs stream it again through imuReader().
  // The camera's span on the IMU clock (t_imu = t_cam + time_offset).
  const int64_t off = static_cast<int64_t>(std::llround(sensors_.camera.time_offset_s * 1e9));
  const int64_t t0 = frames_.front().t_ns + off, t1 = frames_.back().t_ns + off;
  std::vector<std::string> gap_warnings;  // after the reader's, as when the gaps were checked after reading
  ImuCsvStream stream(csv.string(), &warnings_);
  ImuGapCheck gaps(csv.string(), static_cast<int64_t>(std::llround(opt_.max_imu_gap_ms * 1e6)), t0, t1, gap_warnings);
  constexpr size_t kRateSamples = 20001;  // the median step of the first 20000 steps gives the rate
  std::vector<int64_t> t;
  int64_t t_first = 0, t_last = 0;
  size_t count = 0;
  for (ImuSample s; stream.next(s); ++count) {
    gaps.add(s.t_ns, stream.line());
    if (count == 0) t_first = s.t_ns;
    t_last = s.t_ns;
    if (t.size() < kRateSamples) t.push_back(s.t_ns);
  }
  if (count == 0) {
    warnings_.push_back(csv.string() + ": no IMU samples: no IMU data (visual-only runs only)");
    return;
  }
  gaps.finish();
  warnings_.insert(warnings_.end(), gap_warnings.begin(), gap_warnings.end());
  if (t_first > t0)
    warnings_.push_back(csv.string() + ": IMU data starts " + fmt("%.1f", (t_first - t0) * 1e-6) +
                        " ms after the first frame: the frames before it have no IMU data");
  if (t_last < t1)
    warnings_.push_back(csv.string() + ": IMU data ends " + fmt("%.1f", (t1 - t_last) * 1e-6) +
                        " ms before the last frame: the frames after it have no IMU data");

  // Noise densities: explicit file, EuRoC's sensor.yaml, TUM-VI's imu_config.yaml, Kalibr's beside the camchain.
  std::vector<fs::path> candidates;
  if (!opt_.imu_calibration_file.empty()) {
    fs::path p(opt_.imu_calibration_file);
    if (p.is_relative()) p = fs::path(dir_) / p;
    if (!isFile(p)) throw DataError::at(p.string(), 0, "IMU calibration file not found (params.imu_calibration_file)");
    candidates.push_back(p);
  } else {
    candidates = {imu_dir / "sensor.yaml", fs::path(dir_) / "dso" / "imu_config.yaml"};
    if (calib_format_ == "kalibr") {
      const fs::path cd = fs::path(calib_path_).parent_path();
      candidates.push_back(cd / "imu_config.yaml");
      candidates.push_back(cd / "imu.yaml");
    }
  }
  ImuCalibration cal;
  bool found = false;
  for (const auto& p : candidates) {
    if (!isFile(p)) continue;
    cal = readImuYaml(p.string(), warnings_);
    found = true;
    break;
  }
  if (!found)
    warnings_.push_back("no IMU noise calibration found (mav0/imu0/sensor.yaml, dso/imu_config.yaml); using "
                        "rsvio's defaults (EuRoC's ADIS16448 values)");
  sensors_.imu = cal.noise;
  const int64_t step = medianStep(t);
  const double measured_hz = step > 0 ? 1e9 / static_cast<double>(step) : 0.0;
  if (!cal.rate_found && measured_hz > 0) {
    sensors_.imu.rate_hz = measured_hz;
  } else if (measured_hz > 0 && std::abs(measured_hz - cal.noise.rate_hz) > 0.2 * cal.noise.rate_hz) {
    warnings_.push_back("IMU rate in the calibration (" + fmt("%.1f", cal.noise.rate_hz) + " Hz) differs from the data's (" +
                        fmt("%.1f", measured_hz) + " Hz); the noise densities are per sqrt(Hz) either way");
  }
  // Our body frame is the IMU: a EuRoC rig whose IMU is not at the body origin is re-expressed.
  if (!cal.T_B_S.isApprox(Eigen::Isometry3d::Identity()) && calib_format_ == "euroc")
    sensors_.camera.T_B_C = cal.T_B_S.inverse() * sensors_.camera.T_B_C;
  imu_csv_ = csv.string();
  imu_count_ = count;
  sensors_.has_imu = true;
}

namespace {
class CsvImuReader : public ImuReader {
 public:
  explicit CsvImuReader(const std::string& path) : stream_(path, nullptr) {}
  bool next(ImuSample& s) override { return stream_.next(s); }

 private:
  ImuCsvStream stream_;
};

class EmptyImuReader : public ImuReader {
 public:
  bool next(ImuSample&) override { return false; }
};
}  // namespace

std::unique_ptr<ImuReader> EurocSource::imuReader() const {
  if (imu_csv_.empty()) return std::make_unique<EmptyImuReader>();
  return std::make_unique<CsvImuReader>(imu_csv_);
}

const std::vector<ImuSample>& EurocSource::imu() const {
  if (!imu_loaded_ && !imu_csv_.empty()) {
    imu_.reserve(imu_count_);
    auto r = imuReader();
    for (ImuSample s; r->next(s);) imu_.push_back(s);
  }
  imu_loaded_ = true;
  return imu_;
}

}  // namespace rsvio::euroc
