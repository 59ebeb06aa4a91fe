// DSO-style photometric calibration files (contract in rsvio/io/calibration.h).
#include <cmath>
#include <cstdio>
#include <fstream>

#include "rsvio/core/error.h"
#include "rsvio/io/calibration.h"
#include "rsvio/io/csv.h"
#include "rsvio/io/image_file.h"
#include "rsvio/io/trajectory.h"

namespace rsvio::io {

std::vector<float> readInverseResponse(const std::string& path) {
  CsvFormat fmt;
  fmt.delimiter = CsvFormat::Delimiter::kWhitespace;
  CsvReader csv(path, {}, fmt);
  std::vector<float> g;
  std::vector<std::pair<long, int>> where;  // line, column of each value, for the ordering message
  while (csv.next()) {
    for (size_t i = 0; i < csv.size(); ++i) {
      const double v = csv.getDouble(i);
      if (!std::isfinite(v)) throw csv.errorAt(i, "G^-1 value " + std::to_string(g.size()) + " is not finite");
      if (!g.empty() && !(v > g.back())) {
        char buf[160];
        std::snprintf(buf, sizeof(buf), "G^-1 must strictly increase, but value %zu (%.6g) is not greater than "
                      "value %zu (%.6g)", g.size(), v, g.size() - 1, static_cast<double>(g.back()));
        throw csv.errorAt(i, buf);
      }
      g.push_back(static_cast<float>(v));
    }
  }
  if (g.size() != 256 && g.size() != 65536)
    throw DataError::at(path, 0, "expected 256 (8-bit) or 65536 (16-bit) inverse-response values, found " +
                                     std::to_string(g.size()));
  return g;
}

cv::Mat readVignette(const std::string& path, int expected_width, int expected_height) {
  {
    std::ifstream probe(path, std::ios::binary);
    if (!probe) throw DataError::at(path, 0, "cannot open vignette image");
  }
  const bool png_name = path.size() >= 4 && path.compare(path.size() - 4, 4, ".png") == 0;
  if (png_name && !hasPngSignature(path))
    throw DataError::at(path, 0, "vignette is not a PNG file (the file does not start with the PNG signature)");
  cv::Mat img;
  try {
    img = readImage(path);
  } catch (const ImageError& e) {
    throw DataError::at(path, 0, "cannot decode vignette image: " + e.reason());
  }
  if (img.channels() != 1)
    throw DataError::at(path, 0, "vignette must be a single-channel image, found " +
                                     std::to_string(img.channels()) + " channels");
  if (img.depth() != CV_8U && img.depth() != CV_16U)
    throw DataError::at(path, 0, "vignette must be 8- or 16-bit");
  if (expected_width > 0 && (img.cols != expected_width || img.rows != expected_height))
    throw DataError::at(path, 0, "vignette is " + std::to_string(img.cols) + "x" + std::to_string(img.rows) +
                                     ", expected the raw image size " + std::to_string(expected_width) + "x" +
                                     std::to_string(expected_height));
  double max_value = 0.0;
  cv::minMaxLoc(img, nullptr, &max_value);
  if (!(max_value > 0.0)) throw DataError::at(path, 0, "vignette image is all zero");
  cv::Mat v;
  img.convertTo(v, CV_32F, 1.0 / max_value);
  return v;
}

std::vector<ExposureEntry> readExposureTimes(const std::string& path) {
  CsvFormat fmt;
  fmt.delimiter = CsvFormat::Delimiter::kWhitespace;
  CsvReader csv(path, {"id", "time [s]", "exposure [ms]"}, fmt);
  std::vector<ExposureEntry> out;
  while (csv.next()) {
    csv.expectFieldCount(2, 3);
    ExposureEntry e;
    e.id = csv.getString(0);
    e.line = csv.line();
    const auto t = parseSecondsToNs(csv.raw(1));
    if (!t) throw csv.errorAt(1, "expected a time in seconds, found " + quoteFound(csv.raw(1)));
    e.t_ns = *t;
    if (csv.size() == 3) {
      e.exposure_ms = csv.getDouble(2);
      if (!std::isfinite(e.exposure_ms) || !(e.exposure_ms > 0.0))
        throw csv.errorAt(2, "exposure must be a finite number > 0 ms, found " + quoteFound(csv.raw(2)));
    }
    out.push_back(std::move(e));
  }
  return out;
}

}  // namespace rsvio::io
