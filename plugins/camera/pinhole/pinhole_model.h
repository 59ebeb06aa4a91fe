// Typed pinhole camera with three distortion models, the code behind camera.pinhole.
//
// Contract (rsvio/interfaces/camera.h)
// - Camera frame x right, y down, z forward. Pixels of the RAW (distorted) image, pixel centres at
//   integer coordinates: uv = (fx * xd + cx, fy * yd + cy), xd = distort(x / z, y / z).
// - Distortion models (the coefficient order of Kalibr and OpenCV):
//     none         xd = xn
//     radtan       k1 k2 p1 p2 (OpenCV "plumb bob" with k3 = 0, Kalibr "radtan"):
//                    r2 = x^2 + y^2, radial = 1 + k1 r2 + k2 r2^2
//                    xd = x radial + 2 p1 x y + p2 (r2 + 2 x^2)
//                    yd = y radial + p1 (r2 + 2 y^2) + 2 p2 x y
//     equidistant  k1 k2 k3 k4 (Kannala-Brandt as in Kalibr "equidistant" and OpenCV fisheye):
//                    r = |xn|, theta = atan(r), theta_d = theta (1 + k1 th^2 + k2 th^4 + k3 th^6 + k4 th^8)
//                    xd = (theta_d / r) xn
// - Domain: z >= min_depth, and the point inside the radius where the radial polynomial folds over
//   (radtan: first root of d(r radial)/dr, plus det d(xd)/d(xn) > 0 for the tangential part;
//   equidistant: first root of d theta_d / d theta). Beyond it a point would land back inside the
//   image at a wrong place, so it is flagged invalid instead.
// - Unprojection undistorts by Newton's method (2D for radtan, 1D on theta for equidistant) with a
//   residual check; a pixel whose iteration does not converge is invalid.
// - Templated on Scalar (double, float) so tests call the typed code directly; the plugin's adapter
//   (pinhole_camera.cpp) dispatches on the distortion once per batch, not per point.
#pragma once
#include <Eigen/Core>
#include <Eigen/LU>
#include <cmath>
#include <limits>

namespace rsvio::pinhole {

enum class Distortion { kNone, kRadTan, kEquidistant };

template <class Scalar>
class PinholeModel {
 public:
  using Vec2 = Eigen::Matrix<Scalar, 2, 1>;
  using Vec3 = Eigen::Matrix<Scalar, 3, 1>;
  using Vec4 = Eigen::Matrix<Scalar, 4, 1>;
  using Mat22 = Eigen::Matrix<Scalar, 2, 2>;
  using Mat23 = Eigen::Matrix<Scalar, 2, 3>;
  using Mat32 = Eigen::Matrix<Scalar, 3, 2>;

  PinholeModel() = default;
  // intrinsics fx fy cx cy [px]; coeffs as documented above (unused entries ignored for kNone).
  PinholeModel(const Vec4& intrinsics, const Vec4& coeffs, Scalar min_depth)
      : fx_(intrinsics[0]), fy_(intrinsics[1]), cx_(intrinsics[2]), cy_(intrinsics[3]), k_(coeffs),
        min_depth_(min_depth) {
    computeDomain();
  }

  Scalar fx() const { return fx_; }
  Scalar fy() const { return fy_; }
  Scalar cx() const { return cx_; }
  Scalar cy() const { return cy_; }
  const Vec4& coeffs() const { return k_; }
  Scalar minDepth() const { return min_depth_; }

  // Normalised image plane -> distorted normalised coordinates; d_xd_d_xn = d(xd)/d(xn).
  // Returns false outside the model's domain (fold-over of the polynomial).
  template <Distortion D>
  bool distort(const Vec2& xn, Vec2& xd, Mat22* d_xd_d_xn) const {
    if constexpr (D == Distortion::kNone) {
      xd = xn;
      if (d_xd_d_xn) d_xd_d_xn->setIdentity();
      return true;
    } else if constexpr (D == Distortion::kRadTan) {
      return distortRadTan(xn, xd, d_xd_d_xn);
    } else {
      return distortEquidistant(xn, xd, d_xd_d_xn);
    }
  }

  template <Distortion D>
  bool project(const Vec3& p_c, Vec2& uv, Mat23* d_uv_d_p) const {
    const Scalar z = p_c.z();
    using std::isfinite;
    if (!(z >= min_depth_) || !isfinite(z) || !isfinite(p_c.x()) || !isfinite(p_c.y())) return false;
    const Scalar inv_z = Scalar(1) / z;
    const Vec2 xn(p_c.x() * inv_z, p_c.y() * inv_z);
    Vec2 xd;
    Mat22 d_xd_d_xn;
    const bool ok = distort<D>(xn, xd, d_uv_d_p ? &d_xd_d_xn : nullptr);
    uv << fx_ * xd.x() + cx_, fy_ * xd.y() + cy_;
    if (d_uv_d_p) {
      Mat23 d_xn_d_p;
      d_xn_d_p << inv_z, Scalar(0), -xn.x() * inv_z, Scalar(0), inv_z, -xn.y() * inv_z;
      Mat22 d_xd = d_xd_d_xn;
      d_xd.row(0) *= fx_;
      d_xd.row(1) *= fy_;
      *d_uv_d_p = d_xd * d_xn_d_p;
    }
    return ok;
  }

  // Pixel -> unit bearing; d_b_d_uv = d(bearing)/d(uv) (3x2).
  template <Distortion D>
  bool unproject(const Vec2& uv, Vec3& bearing, Mat32* d_b_d_uv) const {
    const Vec2 xd((uv.x() - cx_) / fx_, (uv.y() - cy_) / fy_);
    Vec2 xn;
    if (!undistort<D>(xd, xn)) return false;
    const Vec3 f(xn.x(), xn.y(), Scalar(1));
    const Scalar n = f.norm();
    bearing = f / n;
    if (d_b_d_uv) {
      // bearing = f / |f|: d bearing / d f = (I - b b^T) / |f|; f = (xn, 1); xn = distort^-1(xd).
      Mat22 d_xd_d_xn;
      Vec2 xd_check;
      distort<D>(xn, xd_check, &d_xd_d_xn);
      const Eigen::Matrix<Scalar, 3, 3> d_b_d_f =
          (Eigen::Matrix<Scalar, 3, 3>::Identity() - bearing * bearing.transpose()) / n;
      Mat22 d_xn_d_xd = d_xd_d_xn.inverse();
      d_xn_d_xd.col(0) /= fx_;
      d_xn_d_xd.col(1) /= fy_;
      *d_b_d_uv = d_b_d_f.template leftCols<2>() * d_xn_d_xd;
    }
    return true;
  }

  // Distorted normalised -> undistorted normalised coordinates (Newton with a convergence check).
  template <Distortion D>
  bool undistort(const Vec2& xd, Vec2& xn) const {
    if constexpr (D == Distortion::kNone) {
      xn = xd;
      return true;
    } else if constexpr (D == Distortion::kRadTan) {
      return undistortRadTan(xd, xn);
    } else {
      return undistortEquidistant(xd, xn);
    }
  }

  static constexpr int kMaxUndistortIterations = 30;

  // Largest r^2 = |xn|^2 (radtan) and theta (equidistant) before the radial polynomial folds over.
  Scalar maxRadiusSquared() const { return r2_max_; }
  Scalar maxTheta() const { return theta_max_; }

 private:
  // Newton stops at tolerance(); after the last iteration a residual within 25x of it (the rounding
  // floor of the polynomial) is still accepted, anything larger is a failure to converge.
  static Scalar tolerance() { return Scalar(4) * std::numeric_limits<Scalar>::epsilon(); }

  // The fold-over limits. radtan: d(r radial)/dr = 1 + 3 k1 r^2 + 5 k2 r^4, its first positive root in
  // r^2 (closed form). equidistant: d theta_d / d theta, first root in (0, pi/2) by scan and bisection.
  void computeDomain() {
    r2_max_ = std::numeric_limits<Scalar>::infinity();
    const Scalar a = Scalar(5) * k_[1], b = Scalar(3) * k_[0];
    if (a == Scalar(0)) {
      if (b < Scalar(0)) r2_max_ = -Scalar(1) / b;
    } else {
      const Scalar disc = b * b - Scalar(4) * a;
      if (disc >= Scalar(0)) {
        const Scalar sq = std::sqrt(disc);
        for (Scalar s : {(-b - sq) / (Scalar(2) * a), (-b + sq) / (Scalar(2) * a)})
          if (s > Scalar(0) && s < r2_max_) r2_max_ = s;
      }
    }
    theta_max_ = Scalar(0.5 * M_PI);
    const int n = 2000;
    const Scalar h = theta_max_ / Scalar(n);
    for (int i = 1; i <= n; ++i) {
      Scalar f, df;
      thetaD(h * Scalar(i), f, df);
      if (df > Scalar(0)) continue;
      Scalar lo = h * Scalar(i - 1), hi = h * Scalar(i);
      for (int j = 0; j < 60; ++j) {
        const Scalar mid = Scalar(0.5) * (lo + hi);
        thetaD(mid, f, df);
        (df > Scalar(0) ? lo : hi) = mid;
      }
      theta_max_ = lo;
      break;
    }
  }

  bool distortRadTan(const Vec2& xn, Vec2& xd, Mat22* J) const {
    const Scalar k1 = k_[0], k2 = k_[1], p1 = k_[2], p2 = k_[3];
    const Scalar x = xn.x(), y = xn.y();
    const Scalar x2 = x * x, y2 = y * y, xy = x * y, r2 = x2 + y2;
    const Scalar radial = Scalar(1) + r2 * (k1 + k2 * r2);
    xd.x() = x * radial + Scalar(2) * p1 * xy + p2 * (r2 + Scalar(2) * x2);
    xd.y() = y * radial + p1 * (r2 + Scalar(2) * y2) + Scalar(2) * p2 * xy;
    const Scalar dr = k1 + Scalar(2) * k2 * r2;  // d radial / d r2
    Mat22 d;
    d(0, 0) = radial + Scalar(2) * x2 * dr + Scalar(2) * p1 * y + Scalar(6) * p2 * x;
    d(0, 1) = Scalar(2) * xy * dr + Scalar(2) * p1 * x + Scalar(2) * p2 * y;
    d(1, 0) = d(0, 1);
    d(1, 1) = radial + Scalar(2) * y2 * dr + Scalar(6) * p1 * y + Scalar(2) * p2 * x;
    if (J) *J = d;
    return r2 < r2_max_ && d.determinant() > Scalar(0);
  }

  // theta_d(theta) and its derivative.
  void thetaD(Scalar th, Scalar& th_d, Scalar& d_th_d) const {
    const Scalar t2 = th * th;
    const Scalar poly = Scalar(1) + t2 * (k_[0] + t2 * (k_[1] + t2 * (k_[2] + t2 * k_[3])));
    th_d = th * poly;
    d_th_d = Scalar(1) + t2 * (Scalar(3) * k_[0] +
                               t2 * (Scalar(5) * k_[1] + t2 * (Scalar(7) * k_[2] + t2 * Scalar(9) * k_[3])));
  }

  bool distortEquidistant(const Vec2& xn, Vec2& xd, Mat22* J) const {
    const Scalar r2 = xn.squaredNorm();
    if (r2 < std::numeric_limits<Scalar>::epsilon()) {
      // theta_d / r = 1 + O(r^2): below sqrt(eps) the identity is exact to machine precision.
      xd = xn;
      if (J) J->setIdentity();
      return true;
    }
    const Scalar r = std::sqrt(r2);
    const Scalar th = std::atan(r);
    Scalar th_d, d_th_d;
    thetaD(th, th_d, d_th_d);
    const Scalar s = th_d / r;
    xd = s * xn;
    if (J) {
      // xd = s(r) xn, s = theta_d / r: J = s I + (ds/dr / r) xn xn^T, ds/dr = (theta_d' theta' - s) / r.
      const Scalar ds_dr_over_r = (d_th_d / (Scalar(1) + r2) - s) / r2;
      *J = s * Mat22::Identity() + ds_dr_over_r * xn * xn.transpose();
    }
    return th < theta_max_;
  }

  // Newton on distort(xn) = xd from xn = xd; a step that leaves the invertible region is halved, so
  // the iteration cannot jump over the fold to a false pre-image.
  bool undistortRadTan(const Vec2& xd, Vec2& xn) const {
    xn = xd;
    const Scalar tol = tolerance() * (Scalar(1) + xd.norm());
    Vec2 f;
    Mat22 J;
    if (!distortRadTan(xn, f, &J)) return false;
    for (int i = 0; i < kMaxUndistortIterations; ++i) {
      const Vec2 r = f - xd;
      if (r.norm() <= tol) return true;
      Vec2 step = J.inverse() * r;
      if (!step.allFinite()) return false;
      bool ok = false;
      for (int half = 0; half < 30 && !ok; ++half, step *= Scalar(0.5)) {
        ok = distortRadTan(Vec2(xn - step), f, &J);
        if (ok) xn -= step;
      }
      if (!ok) return false;
    }
    return (f - xd).norm() <= Scalar(25) * tol;
  }

  // theta_d is increasing on [0, theta_max): Newton safeguarded by bisection on that bracket.
  bool undistortEquidistant(const Vec2& xd, Vec2& xn) const {
    const Scalar th_d = xd.norm();
    if (th_d * th_d < std::numeric_limits<Scalar>::epsilon()) {
      xn = xd;
      return true;
    }
    Scalar lo = Scalar(0), hi = theta_max_;
    Scalar f, df;
    thetaD(hi, f, df);
    if (!(th_d < f)) return false;  // beyond the largest distorted angle the model can produce
    Scalar th = th_d < hi ? th_d : Scalar(0.5) * hi;
    const Scalar tol = tolerance() * (Scalar(1) + th_d);
    for (int i = 0; i < kMaxUndistortIterations; ++i) {
      thetaD(th, f, df);
      const Scalar r = f - th_d;
      if (std::abs(r) <= tol) {
        xn = xd * (std::tan(th) / th_d);
        return true;
      }
      (r > Scalar(0) ? hi : lo) = th;
      Scalar next = th - r / df;
      if (!(next > lo && next < hi)) next = Scalar(0.5) * (lo + hi);
      th = next;
    }
    thetaD(th, f, df);
    if (std::abs(f - th_d) > Scalar(25) * tol) return false;
    xn = xd * (std::tan(th) / th_d);
    return true;
  }

  Scalar fx_ = Scalar(1), fy_ = Scalar(1), cx_ = Scalar(0), cy_ = Scalar(0);
  Vec4 k_ = Vec4::Zero();
  Scalar min_depth_ = Scalar(1e-3);
  Scalar r2_max_ = std::numeric_limits<Scalar>::infinity();
  Scalar theta_max_ = Scalar(0.5 * M_PI);
};

}  // namespace rsvio::pinhole
