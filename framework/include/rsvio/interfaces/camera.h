// Interface of camera.* plugins: projection and distortion of the RAW image.
//
// Contract
// - Camera frame: x right, y down, z forward. Pixels: raw (distorted) image, pixel centres at integer
//   coordinates, u to the right, v down. rsvio works on raw images and projects through the distortion,
//   so a projected v IS the raw row that gives the capture time (conventions.md, paper eq. 7 without
//   undistorting the image).
// - Batch calls: one virtual call per batch of points (Basalt's lesson); implementations keep the
//   model as a typed template behind this thin adapter so tests can call the typed code directly.
// - project: p_c (3xN) -> uv (2xN). valid[i] = 0 when the point is behind the camera (z < min depth) or
//   outside the model's domain; uv of invalid points is unspecified. d_uv_d_p, when given, receives
//   the 2x3 Jacobian d(uv)/d(p_c) per point.
// - unproject: uv (2xN) -> unit bearing vectors (3xN), with d(bearing)/d(uv) (3x2) when asked.
// - Intrinsics come from the dataset's calibration through setCalibration(); a model that cannot
//   represent the calibration (unknown distortion name) throws ConfigError naming it. Never silently
//   falls back to another model.
#pragma once
#include <Eigen/Core>
#include <vector>

#include "rsvio/core/types.h"
#include "rsvio/plugin/plugin.h"

namespace rsvio {

using Jac23 = Eigen::Matrix<double, 2, 3>;
using Jac32 = Eigen::Matrix<double, 3, 2>;

class CameraModel : public PluginBase {
 public:
  static constexpr PluginKind kKind = PluginKind::Camera;

  virtual void setCalibration(const CameraCalibration& calib) = 0;
  virtual const CameraCalibration& calibration() const = 0;
  int width() const { return calibration().width; }
  int height() const { return calibration().height; }

  virtual void project(const Eigen::Matrix3Xd& p_c, Eigen::Matrix2Xd& uv, std::vector<uint8_t>& valid,
                       std::vector<Jac23>* d_uv_d_p = nullptr) const = 0;
  virtual void unproject(const Eigen::Matrix2Xd& uv, Eigen::Matrix3Xd& bearing, std::vector<uint8_t>& valid,
                         std::vector<Jac32>* d_bearing_d_uv = nullptr) const = 0;

  // Single-point convenience (not for hot loops).
  bool project(const Vec3& p_c, Vec2& uv, Jac23* d_uv_d_p = nullptr) const;
  bool unproject(const Vec2& uv, Vec3& bearing) const;
  bool inImage(const Vec2& uv, double border_px = 0.0) const {
    return uv.x() >= border_px && uv.y() >= border_px && uv.x() <= width() - 1 - border_px &&
           uv.y() <= height() - 1 - border_px;
  }
};

}  // namespace rsvio
