// Image pyramid with gradients: the image representation every photometric residual samples.
//
// Contract
// - Input: one CV_32F image in the photometric working domain (photometric models already applied,
//   see prepareWorkingImage below), RAW (distorted) geometry, pixel centres at integer coordinates.
// - Level 0 is the input; level l+1 averages 2x2 blocks of level l (width and height halved, rounded
//   down). A level-0 pixel coordinate x maps to level l as x_l = (x + 0.5) / 2^l - 0.5 (pixel centres
//   stay centres), so d x_l / d x = 2^-l. Use toLevel()/fromLevel(); never divide by 2^l alone.
// - Each pixel stores (I, gx, gy, |g|^2) interleaved (16 bytes): gx, gy are central differences
//   0.5 * (I[x+1] - I[x-1]) in intensity per level pixel (DSO's convention), zero on the outermost
//   row/column. Bilinear sampling interpolates all four channels at once (one 16-byte load per tap).
// - Rows are contiguous; stride == width. Memory is owned by the pyramid; levels never reallocate
//   after construction, so pointers stay valid for the pyramid's lifetime.
#pragma once
#include <Eigen/Core>
#include <cmath>
#include <memory>
#include <opencv2/core.hpp>
#include <vector>

#include "rsvio/core/types.h"

namespace rsvio {

class PhotometricModel;

// One pyramid level. All sampling functions are inline: they run in the innermost loops.
class ImageLevel {
 public:
  ImageLevel() = default;
  ImageLevel(int width, int height, int level);

  int width() const { return width_; }
  int height() const { return height_; }
  int level() const { return level_; }
  float scale() const { return scale_; }  // 2^level: level-0 pixels per level pixel

  const float* data() const { return data_.data(); }  // (I, gx, gy, |g|^2) per pixel
  float* data() { return data_.data(); }
  const float* pixel(int x, int y) const { return data_.data() + 4 * (static_cast<size_t>(y) * width_ + x); }
  float intensity(int x, int y) const { return pixel(x, y)[0]; }
  float gradSquared(int x, int y) const { return pixel(x, y)[3]; }

  // Level-0 coordinate -> this level, and back (pixel centres at integers on every level).
  float toLevel(float x0) const { return (x0 + 0.5f) / scale_ - 0.5f; }
  float fromLevel(float xl) const { return (xl + 0.5f) * scale_ - 0.5f; }

  // True if (u, v) can be sampled bilinearly with `margin` level pixels of border left.
  bool inside(float u, float v, float margin) const {
    return u >= margin && v >= margin && u <= width_ - 1 - margin && v <= height_ - 1 - margin;
  }

  // Bilinear interpolation of (I, gx, gy, |g|^2) at (u, v); caller guarantees inside(u, v, 0) and that
  // u < width-1, v < height-1 (inside(u, v, 1) is the usual guard). out must hold 4 floats.
  void sample(float u, float v, float* out) const {
    const int ix = static_cast<int>(u);
    const int iy = static_cast<int>(v);
    const float dx = u - ix;
    const float dy = v - iy;
    const float* p = pixel(ix, iy);
    const float* q = p + 4 * width_;
    using A4 = Eigen::Array4f;
    const A4 r = (1.f - dy) * ((1.f - dx) * Eigen::Map<const A4>(p) + dx * Eigen::Map<const A4>(p + 4)) +
                 dy * ((1.f - dx) * Eigen::Map<const A4>(q) + dx * Eigen::Map<const A4>(q + 4));
    Eigen::Map<A4> dst(out);
    dst = r;
  }

  // Interpolated intensity only.
  float sampleIntensity(float u, float v) const {
    const int ix = static_cast<int>(u);
    const int iy = static_cast<int>(v);
    const float dx = u - ix;
    const float dy = v - iy;
    const float* p = pixel(ix, iy);
    const float* q = p + 4 * width_;
    return (1.f - dy) * ((1.f - dx) * p[0] + dx * p[4]) + dy * ((1.f - dx) * q[0] + dx * q[4]);
  }

 private:
  friend class ImagePyramid;
  int width_ = 0;
  int height_ = 0;
  int level_ = 0;
  float scale_ = 1.f;
  std::vector<float> data_;
};

class ImagePyramid {
 public:
  ImagePyramid() = default;
  // Builds `num_levels` levels (fewer if a level would be smaller than min_size_px on either side).
  // image: CV_32F, one channel. Throws Error for an empty image or wrong type.
  ImagePyramid(const cv::Mat& image_f32, int num_levels, int min_size_px = 16);

  int numLevels() const { return static_cast<int>(levels_.size()); }
  const ImageLevel& level(int l) const { return levels_[l]; }
  int width() const { return levels_.empty() ? 0 : levels_[0].width(); }
  int height() const { return levels_.empty() ? 0 : levels_[0].height(); }

 private:
  std::vector<ImageLevel> levels_;
};

// Number of levels such that the coarsest is at least min_size_px on its shorter side, capped at max.
int pyramidLevelsFor(int width, int height, int max_levels, int min_size_px = 16);

// Raw frame -> CV_32F working image: 8-bit values as they are, 16-bit (and other depths) scaled so that
// 0..255 spans the raw range (interfaces/photometric.h), then every photometric model's correct() in
// slot order. Throws DataError naming the frame for an empty or multi-channel image.
cv::Mat prepareWorkingImage(const Frame& frame, const std::vector<const PhotometricModel*>& models);

}  // namespace rsvio
