// The simulator's own pinhole + distortion model, used to cast a ray through every (sub)pixel of the
// raw image. Independent of the camera.* plugins on purpose: the simulator is the ground truth the
// estimator's camera models are tested against.
//
// Contract: camera x right, y down, z forward; raw (distorted) pixels with centres at integer
// coordinates, uv = (fx xd + cx, fy yd + cy). Distortion models with Kalibr's coefficient order:
//   none; radtan k1 k2 p1 p2 (xd = x (1 + k1 r^2 + k2 r^4) + 2 p1 x y + p2 (r^2 + 2 x^2), y alike);
//   equidistant k1..k4 (theta_d = theta (1 + k1 theta^2 + k2 theta^4 + k3 theta^6 + k4 theta^8),
//   theta = atan(r), xd = theta_d / r * xn).
#pragma once
#include "rsvio/core/types.h"

namespace rsvio::sim {

class Lens {
 public:
  explicit Lens(const CameraCalibration& calib);
  bool project(const Vec3& p_c, Vec2& uv) const;  // false behind the camera
  // The ray (xn, yn, 1) of a raw pixel. False when the distortion cannot be inverted there.
  bool unproject(const Vec2& uv, Vec3& ray) const;
  Vec2 distort(const Vec2& xn) const;
  bool undistort(const Vec2& xd, Vec2& xn) const;

 private:
  enum class Model { kNone, kRadTan, kEquidistant } model_ = Model::kNone;
  double fx_, fy_, cx_, cy_;
  double k_[4] = {0, 0, 0, 0};
};

}  // namespace rsvio::sim
