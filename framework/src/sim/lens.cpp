// Projection and unprojection through the distortion (rsvio/sim/lens.h).
#include "rsvio/sim/lens.h"

#include <Eigen/LU>
#include <cmath>

#include "rsvio/core/error.h"

namespace rsvio::sim {

Lens::Lens(const CameraCalibration& c)
    : fx_(c.intrinsics[0]), fy_(c.intrinsics[1]), cx_(c.intrinsics[2]), cy_(c.intrinsics[3]) {
  if (c.distortion == "none" || c.distortion.empty()) {
    model_ = Model::kNone;
  } else if (c.distortion == "radtan" || c.distortion == "radial-tangential") {
    model_ = Model::kRadTan;
  } else if (c.distortion == "equidistant") {
    model_ = Model::kEquidistant;
  } else {
    throw ConfigError("camera distortion '" + c.distortion + "' is not one of none, radtan, equidistant");
  }
  if (model_ != Model::kNone && c.distortion_coeffs.size() != 4)
    throw ConfigError("camera distortion '" + c.distortion + "' needs 4 coefficients");
  for (int i = 0; model_ != Model::kNone && i < 4; ++i) k_[i] = c.distortion_coeffs[i];
}

Vec2 Lens::distort(const Vec2& xn) const {
  switch (model_) {
    case Model::kNone: return xn;
    case Model::kRadTan: {
      const double x = xn.x(), y = xn.y(), r2 = x * x + y * y;
      const double radial = 1.0 + r2 * (k_[0] + k_[1] * r2);
      return Vec2(x * radial + 2 * k_[2] * x * y + k_[3] * (r2 + 2 * x * x),
                  y * radial + k_[2] * (r2 + 2 * y * y) + 2 * k_[3] * x * y);
    }
    case Model::kEquidistant: {
      const double r = xn.norm();
      if (r < 1e-12) return xn;
      const double th = std::atan(r), t2 = th * th;
      const double th_d = th * (1.0 + t2 * (k_[0] + t2 * (k_[1] + t2 * (k_[2] + t2 * k_[3]))));
      return xn * (th_d / r);
    }
  }
  return xn;
}

bool Lens::undistort(const Vec2& xd, Vec2& xn) const {
  switch (model_) {
    case Model::kNone: xn = xd; return true;
    case Model::kRadTan: {
      // Newton with a numeric 2x2 Jacobian; converges in a few steps for lens-like coefficients.
      xn = xd;
      for (int it = 0; it < 50; ++it) {
        const Vec2 r = distort(xn) - xd;
        if (r.norm() < 1e-13) return true;
        Eigen::Matrix2d J;
        const double h = 1e-7;
        for (int j = 0; j < 2; ++j) {
          Vec2 d = Vec2::Zero();
          d[j] = h;
          J.col(j) = (distort(xn + d) - distort(xn - d)) / (2 * h);
        }
        if (!(J.determinant() > 0)) return false;
        xn -= J.inverse() * r;
        if (!xn.allFinite()) return false;
      }
      return (distort(xn) - xd).norm() < 1e-9;
    }
    case Model::kEquidistant: {
      const double th_d = xd.norm();
      if (th_d < 1e-12) {
        xn = xd;
        return true;
      }
      double th = th_d;
      for (int it = 0; it < 50; ++it) {
        const double t2 = th * th;
        const double f = th * (1.0 + t2 * (k_[0] + t2 * (k_[1] + t2 * (k_[2] + t2 * k_[3])))) - th_d;
        const double df = 1.0 + t2 * (3 * k_[0] + t2 * (5 * k_[1] + t2 * (7 * k_[2] + t2 * 9 * k_[3])));
        if (!(df > 0)) return false;
        th -= f / df;
        if (std::abs(f) < 1e-14) break;
      }
      if (!(th > 0 && th < 1.5607)) return false;  // beyond ~89.4 deg the pinhole ray has no z > 0
      xn = xd * (std::tan(th) / th_d);
      return (distort(xn) - xd).norm() < 1e-9;
    }
  }
  return false;
}

bool Lens::project(const Vec3& p, Vec2& uv) const {
  if (!(p.z() > 1e-9)) return false;
  const Vec2 xd = distort(Vec2(p.x() / p.z(), p.y() / p.z()));
  uv = Vec2(fx_ * xd.x() + cx_, fy_ * xd.y() + cy_);
  return true;
}

bool Lens::unproject(const Vec2& uv, Vec3& ray) const {
  Vec2 xn;
  if (!undistort(Vec2((uv.x() - cx_) / fx_, (uv.y() - cy_) / fy_), xn)) return false;
  ray = Vec3(xn.x(), xn.y(), 1.0);
  return true;
}

}  // namespace rsvio::sim
