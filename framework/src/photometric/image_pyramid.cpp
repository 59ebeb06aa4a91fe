#include "rsvio/photometric/image_pyramid.h"

#include <algorithm>
#include <string>

#include "rsvio/core/error.h"
#include "rsvio/interfaces/photometric.h"

namespace rsvio {

ImageLevel::ImageLevel(int width, int height, int level)
    : width_(width), height_(height), level_(level), scale_(static_cast<float>(1 << level)) {
  data_.assign(static_cast<size_t>(width) * height * 4, 0.f);
}

namespace {

// Central-difference gradients and |g|^2 of the intensity channel; zero on the outer frame so that a
// border pixel never claims an edge it cannot see.
void computeGradients(ImageLevel& L) {
  const int w = L.width();
  const int h = L.height();
  float* d = L.data();
  for (int y = 0; y < h; ++y) {
    float* row = d + 4 * static_cast<size_t>(y) * w;
    if (y == 0 || y == h - 1) {
      for (int x = 0; x < w; ++x) row[4 * x + 1] = row[4 * x + 2] = row[4 * x + 3] = 0.f;
      continue;
    }
    const float* up = row - 4 * w;
    const float* dn = row + 4 * w;
    row[1] = row[2] = row[3] = 0.f;
    for (int x = 1; x < w - 1; ++x) {
      const float gx = 0.5f * (row[4 * (x + 1)] - row[4 * (x - 1)]);
      const float gy = 0.5f * (dn[4 * x] - up[4 * x]);
      row[4 * x + 1] = gx;
      row[4 * x + 2] = gy;
      row[4 * x + 3] = gx * gx + gy * gy;
    }
    float* last = row + 4 * (w - 1);
    last[1] = last[2] = last[3] = 0.f;
  }
}

}  // namespace

int pyramidLevelsFor(int width, int height, int max_levels, int min_size_px) {
  int levels = 1;
  int w = width, h = height;
  while (levels < max_levels && w / 2 >= min_size_px && h / 2 >= min_size_px) {
    w /= 2;
    h /= 2;
    ++levels;
  }
  return levels;
}

ImagePyramid::ImagePyramid(const cv::Mat& image, int num_levels, int min_size_px) {
  if (image.empty() || image.type() != CV_32FC1)
    throw Error("ImagePyramid: expected a non-empty CV_32FC1 image");
  const int n = pyramidLevelsFor(image.cols, image.rows, std::max(1, num_levels), min_size_px);
  levels_.reserve(n);
  levels_.emplace_back(image.cols, image.rows, 0);
  {
    ImageLevel& L0 = levels_[0];
    for (int y = 0; y < image.rows; ++y) {
      const float* src = image.ptr<float>(y);
      float* dst = L0.data() + 4 * static_cast<size_t>(y) * image.cols;
      for (int x = 0; x < image.cols; ++x) dst[4 * x] = src[x];
    }
    computeGradients(L0);
  }
  for (int l = 1; l < n; ++l) {
    const ImageLevel& P = levels_[l - 1];
    ImageLevel L(P.width() / 2, P.height() / 2, l);
    for (int y = 0; y < L.height(); ++y) {
      const float* a = P.pixel(0, 2 * y);
      const float* b = P.pixel(0, 2 * y + 1);
      float* dst = L.data() + 4 * static_cast<size_t>(y) * L.width();
      for (int x = 0; x < L.width(); ++x)
        dst[4 * x] = 0.25f * (a[8 * x] + a[8 * x + 4] + b[8 * x] + b[8 * x + 4]);
    }
    computeGradients(L);
    levels_.push_back(std::move(L));
  }
}

cv::Mat prepareWorkingImage(const Frame& frame, const std::vector<const PhotometricModel*>& models) {
  const std::string where = "frame " + std::to_string(frame.index) + " (t_ns " + std::to_string(frame.t_ns) +
                            (frame.path.empty() ? "" : ", " + frame.path) + ")";
  if (frame.image.empty()) throw DataError(where + ": empty image");
  if (frame.image.channels() != 1)
    throw DataError(where + ": expected a single-channel image, found " + std::to_string(frame.image.channels()) +
                    " channels");
  cv::Mat f;
  switch (frame.image.depth()) {
    case CV_8U: frame.image.convertTo(f, CV_32F); break;
    case CV_16U: frame.image.convertTo(f, CV_32F, 255.0 / 65535.0); break;
    case CV_32F: f = frame.image.clone(); break;
    default: throw DataError(where + ": unsupported image depth (expected 8 or 16 bit)");
  }
  for (const PhotometricModel* m : models)
    if (m) m->correct(f, frame);
  return f;
}

}  // namespace rsvio
