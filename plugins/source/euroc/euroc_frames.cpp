// source.euroc: images read on demand, photometric calibration and resizing (contract in euroc_source.h).
#include <cmath>
#include <filesystem>
#include <map>
#include <opencv2/imgproc.hpp>

#include "dataset_index.h"
#include "euroc_source.h"
#include "rsvio/core/error.h"
#include "rsvio/io/calibration.h"
#include "rsvio/io/image_file.h"

namespace fs = std::filesystem;

namespace rsvio::euroc {
namespace {

std::string size(int w, int h) { return std::to_string(w) + "x" + std::to_string(h); }

bool endsWith(const std::string& s, const char* suffix) {
  const std::string x(suffix);
  if (s.size() < x.size()) return false;
  std::string tail = s.substr(s.size() - x.size());
  for (char& c : tail) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return tail == x;
}

}  // namespace

std::string EurocSource::frameLabel(size_t i) const {
  const FrameEntry& f = frames_[i];
  return f.path + ": frame " + std::to_string(i) + " (timestamp " + std::to_string(f.stamp_ns) + " ns, " +
         index_path_ + ":" + std::to_string(f.line) + ")";
}

cv::Mat EurocSource::loadRaw(size_t i) const {
  const FrameEntry& f = frames_[i];
  std::error_code ec;
  if (!fs::is_regular_file(f.path, ec)) throw DataError(frameLabel(i) + ": image not found");
  if (endsWith(f.path, ".png") && !io::hasPngSignature(f.path))
    throw DataError(frameLabel(i) + ": not a PNG file (it does not start with the PNG signature; "
                                    "empty, truncated or another format renamed?)");
  cv::Mat img;
  try {
    img = io::readImage(f.path);  // PNG or JPEG, as cv::imread(IMREAD_UNCHANGED)
  } catch (const io::ImageError& e) {
    throw DataError(frameLabel(i) + ": cannot read or decode image: " + e.reason());
  }
  if (img.depth() != CV_8U && img.depth() != CV_16U)
    throw DataError(frameLabel(i) + ": unsupported pixel depth (expected 8- or 16-bit)");
  if (img.channels() == 3 || img.channels() == 4) {
    // Colour recordings are used as grey: the direct residuals work on intensities.
    cv::Mat grey;
    cv::cvtColor(img, grey, img.channels() == 3 ? cv::COLOR_BGR2GRAY : cv::COLOR_BGRA2GRAY);
    img = grey;
  } else if (img.channels() != 1) {
    throw DataError(frameLabel(i) + ": unsupported image with " + std::to_string(img.channels()) + " channels");
  }
  if (img.cols != raw_width_ || img.rows != raw_height_)
    throw DataError(frameLabel(i) + ": image is " + size(img.cols, img.rows) + ", expected " +
                    size(raw_width_, raw_height_) + " from the calibration " + calib_path_);
  return img;
}

Frame EurocSource::readFrame(size_t i) const {
  if (i >= frames_.size())
    throw Error("source.euroc: frame " + std::to_string(i) + " out of range (" + std::to_string(frames_.size()) +
                " frames)");
  const FrameEntry& f = frames_[i];
  Frame out;
  out.index = static_cast<int64_t>(i);
  out.t_ns = f.t_ns;
  out.exposure_ms = f.exposure_ms;
  out.path = f.path;
  cv::Mat raw = loadRaw(i);
  if (raw.cols != sensors_.camera.width || raw.rows != sensors_.camera.height)
    cv::resize(raw, out.image, cv::Size(sensors_.camera.width, sensors_.camera.height), 0, 0, cv::INTER_AREA);
  else
    out.image = raw;
  return out;
}

void EurocSource::readPhotometric() {
  const fs::path d(dir_);
  fs::path folder;
  for (const fs::path& c : {d / "dso" / opt_.camera, fs::path(cam_dir_)}) {
    std::error_code ec;
    if (fs::is_regular_file(c / "pcalib.txt", ec) || fs::is_regular_file(c / "vignette.png", ec) ||
        fs::is_regular_file(c / "times.txt", ec)) {
      folder = c;
      break;
    }
  }
  if (folder.empty()) return;
  PhotometricCalibration& ph = sensors_.photometric;
  std::error_code ec;
  if (fs::is_regular_file(folder / "pcalib.txt", ec)) {
    ph.response_path = (folder / "pcalib.txt").string();
    ph.inverse_response = io::readInverseResponse(ph.response_path);
  }
  if (fs::is_regular_file(folder / "vignette.png", ec)) {
    ph.vignette_path = (folder / "vignette.png").string();
    ph.vignette = io::readVignette(ph.vignette_path, raw_width_, raw_height_);
  }
  const fs::path times = folder / "times.txt";
  if (!fs::is_regular_file(times, ec)) return;
  const auto entries = io::readExposureTimes(times.string());
  std::map<std::string, double> by_id;
  std::map<int64_t, double> by_time;
  for (const auto& e : entries) {
    by_id[e.id] = e.exposure_ms;
    by_time[e.t_ns] = e.exposure_ms;
  }
  size_t missing = 0;
  for (auto& f : frames_) {
    const std::string stem = fs::path(f.path).stem().string();
    auto it = by_id.find(stem);
    if (it != by_id.end()) {
      f.exposure_ms = it->second;
      continue;
    }
    // times.txt stamps in seconds may be rounded: accept the nearest within 1 us.
    auto jt = by_time.lower_bound(f.stamp_ns - 1000);
    if (jt != by_time.end() && std::llabs(jt->first - f.stamp_ns) <= 1000)
      f.exposure_ms = jt->second;
    else
      ++missing;
  }
  if (missing > 0)
    warnings_.push_back(times.string() + ": no exposure time for " + std::to_string(missing) + " of " +
                        std::to_string(frames_.size()) + " frames (matched by image name, then by time)");
}

void EurocSource::applyScale() {
  CameraCalibration& c = sensors_.camera;
  if (opt_.image_scale == 1.0) return;
  const int w = std::max(1, static_cast<int>(std::lround(raw_width_ * opt_.image_scale)));
  const int h = std::max(1, static_cast<int>(std::lround(raw_height_ * opt_.image_scale)));
  const double sx = static_cast<double>(w) / raw_width_, sy = static_cast<double>(h) / raw_height_;
  // Pixel centres at integer coordinates: u' = sx * (u + 0.5) - 0.5.
  c.intrinsics = Eigen::Vector4d(sx * c.intrinsics[0], sy * c.intrinsics[1], sx * (c.intrinsics[2] + 0.5) - 0.5,
                                 sy * (c.intrinsics[3] + 0.5) - 0.5);
  c.width = w;
  c.height = h;
  // Working row r' covers raw rows around (r' + 0.5) / sy - 0.5: the same readout time spreads over
  // fewer rows, so the delay per row grows by 1 / sy and frame times (middle row) stay unchanged.
  c.line_delay_s /= sy;
  if (!sensors_.photometric.vignette.empty()) {
    cv::Mat v;
    cv::resize(sensors_.photometric.vignette, v, cv::Size(w, h), 0, 0, cv::INTER_AREA);
    sensors_.photometric.vignette = v;
  }
}

}  // namespace rsvio::euroc
