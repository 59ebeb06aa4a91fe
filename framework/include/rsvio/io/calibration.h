// Calibration files the framework reads without YAML: DSO-style photometric calibration.
// (Geometric calibration in YAML - EuRoC sensor.yaml, Kalibr camchain - is read inside the source.euroc
// plugin, the only place that links yaml-cpp.)
//
// Formats (as DSO, TUM monoVO, TUM-VI and the TUM rolling-shutter dataset publish them)
// - pcalib.txt: the inverse response G^-1, whitespace-separated numbers, one per raw value: 256 for
//   8-bit images, 65536 for 16-bit ones. Entry k is the irradiance that produced raw value k, so the
//   values must strictly increase (DSO rejects a non-increasing G^-1 too). Kept as written, not rescaled.
// - vignette.png: 8- or 16-bit single-channel image of the raw image's size; returned as CV_32F divided
//   by its maximum, so the brightest (centre) pixel is 1 and V(x) lies in [0, 1].
// - times.txt: one line per frame "<id> <time [s]> [<exposure [ms]>]", whitespace separated, '#'
//   comments. id is the image file's stem (TUM-VI/TUM RS: the nanosecond stamp; TUM monoVO: "00042").
//   Exposure times must be finite and > 0; a file without the third column has no exposures.
// - Errors are DataError "path:line:col: field 'x': ..." (see rsvio/io/csv.h); nothing here crashes.
#pragma once
#include <cstdint>
#include <limits>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace rsvio::io {

// Reads pcalib.txt. Throws DataError on a non-number, a non-finite value, a count other than 256 or
// 65536, or a value not greater than the one before it.
std::vector<float> readInverseResponse(const std::string& path);

// Reads vignette.png. Throws DataError when the file is missing or not a decodable image, has more than
// one channel, a depth other than 8/16 bit, an all-zero content, or (when expected_width > 0) a size
// other than expected_width x expected_height.
cv::Mat readVignette(const std::string& path, int expected_width = 0, int expected_height = 0);

struct ExposureEntry {
  std::string id;        // image file stem
  int64_t t_ns = 0;      // the time column, exactly converted from decimal seconds
  double exposure_ms = std::numeric_limits<double>::quiet_NaN();  // NaN when the file has no third column
  long line = 0;         // line in times.txt, for messages
};

// Reads times.txt. Throws DataError on rows with fewer than 2 or more than 3 fields, a bad time, or a
// non-finite or non-positive exposure.
std::vector<ExposureEntry> readExposureTimes(const std::string& path);

}  // namespace rsvio::io
