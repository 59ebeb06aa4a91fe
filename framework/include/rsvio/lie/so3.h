// SO3<S>: rotations of 3D space. Invariant: q_ is a unit quaternion (|q|^2 = 1 up to rounding; every
// constructor checks or renormalises, composition renormalises when it drifts past epsilon). q and -q
// are the same rotation; log() returns the rotation vector of angle in [0, pi].
// Tangent: rotation vector omega (axis * angle), exp(omega) = I + sin(t)/t [w]x + (1-cos t)/t^2 [w]x^2.
// Conventions of the whole module (perturbation side, Adj, frames): lie.h.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <cmath>
#include <random>
#include <sstream>
#include <string>

#include "rsvio/core/error.h"
#include "rsvio/lie/lie_common.h"

namespace rsvio {

template <class Scalar_>
class SO3 {
 public:
  using Scalar = Scalar_;
  static constexpr int DoF = 3;             // tangent dimension
  static constexpr int num_parameters = 4;  // stored quaternion (x, y, z, w)
  using Tangent = Eigen::Matrix<Scalar, 3, 1>;
  using Point = Eigen::Matrix<Scalar, 3, 1>;
  using Transformation = Eigen::Matrix<Scalar, 3, 3>;
  using Adjoint = Eigen::Matrix<Scalar, 3, 3>;
  using QuaternionType = Eigen::Quaternion<Scalar>;
  using Constants = lie::Constants<Scalar>;

  SO3() : q_(QuaternionType::Identity()) {}
  // Throws rsvio::Error unless | |q|^2 - 1 | <= unitTolerance; stores q renormalised.
  explicit SO3(const QuaternionType& q) : q_(q) {
    using std::abs;
    if (!(abs(q.squaredNorm() - Scalar(1)) <= Constants::unitTolerance()))
      throw Error("SO3: quaternion is not of unit norm (|q|^2 = " + str(q.squaredNorm()) +
                  "); use setQuaternion() to normalise");
    q_.normalize();
  }
  // Throws rsvio::Error unless R^T R = I (within unitTolerance) and det R > 0.
  explicit SO3(const Transformation& R) {
    using std::abs;
    const Scalar err = (R.transpose() * R - Transformation::Identity()).cwiseAbs().maxCoeff();
    if (!(err <= Constants::unitTolerance()) || !(R.determinant() > Scalar(0)))
      throw Error("SO3: matrix is not a rotation (max |R^T R - I| = " + str(err) +
                  ", det = " + str(R.determinant()) + "); use SO3::fitToSO3()");
    q_ = QuaternionType(R);
    q_.normalize();
  }

  static SO3 Identity() { return SO3(); }

  // Nearest rotation in the Frobenius norm (SVD), for matrices that are only roughly orthonormal.
  static SO3 fitToSO3(const Transformation& M) {
    Eigen::JacobiSVD<Transformation> svd(M, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Transformation D = Transformation::Identity();
    D(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < Scalar(0) ? Scalar(-1) : Scalar(1);
    return fromQuaternionUnchecked(QuaternionType(svd.matrixU() * D * svd.matrixV().transpose()).normalized());
  }

  // Normalises q; throws rsvio::Error if |q| is (nearly) zero, where no rotation is meant.
  void setQuaternion(const QuaternionType& q) {
    using std::sqrt;
    const Scalar n = sqrt(q.squaredNorm());
    if (!(n >= Constants::epsilon()))
      throw Error("SO3::setQuaternion: quaternion norm " + str(n) + " is too close to zero");
    q_ = QuaternionType(q.coeffs() / n);
  }

  static SO3 exp(const Tangent& omega) {
    using std::cos;
    using std::sqrt;
    const Scalar theta = sqrt(omega.squaredNorm());
    const Scalar half = theta / Scalar(2);
    // sin(theta/2) / theta = a(theta/2) / 2, no division at theta = 0.
    const Scalar k = lie::sinOverTheta(half) / Scalar(2);
    const Tangent v = k * omega;
    return fromQuaternionUnchecked(QuaternionType(cos(half), v.x(), v.y(), v.z()));
  }

  // Rotation vector with angle in [0, pi]. At exactly pi either axis sign may come out.
  Tangent log() const {
    using std::atan2;
    using std::sqrt;
    const Scalar n = sqrt(q_.vec().squaredNorm());
    Scalar w = q_.w();
    Scalar sign(1);
    if (w < Scalar(0)) {  // pick the representative with angle <= pi
      w = -w;
      sign = Scalar(-1);
    }
    Scalar factor;
    if (n < Constants::epsilon()) {
      // 2 atan(n / w) / n = (2 / w) (1 - n^2 / (3 w^2) + ...), w ~ 1 here.
      factor = Scalar(2) / w * (Scalar(1) - n * n / (Scalar(3) * w * w));
    } else {
      factor = Scalar(2) * atan2(n, w) / n;  // atan2 keeps full precision near pi (w -> 0)
    }
    return sign * factor * q_.vec();
  }

  // Rotation angle in [0, pi].
  Scalar angle() const {
    using std::abs;
    using std::atan2;
    using std::sqrt;
    return Scalar(2) * atan2(sqrt(q_.vec().squaredNorm()), abs(q_.w()));
  }

  static Transformation hat(const Tangent& omega) { return lie::skew(omega); }
  // Inverse of hat; reads the antisymmetric part, so a nearly skew matrix gives the nearest omega.
  static Tangent vee(const Transformation& W) {
    return Tangent(W(2, 1) - W(1, 2), W(0, 2) - W(2, 0), W(1, 0) - W(0, 1)) / Scalar(2);
  }

  SO3 inverse() const { return fromQuaternionUnchecked(q_.conjugate()); }
  // R exp(d) = exp(R d) R (paper eq. 26 restricted to rotations).
  Adjoint Adj() const { return matrix(); }
  Transformation matrix() const { return q_.toRotationMatrix(); }
  Transformation rotationMatrix() const { return matrix(); }
  const QuaternionType& unit_quaternion() const { return q_; }
  // Parameters in Eigen's storage order (x, y, z, w); data() points at them.
  Eigen::Matrix<Scalar, 4, 1> params() const { return q_.coeffs(); }
  const Scalar* data() const { return q_.coeffs().data(); }

  template <class T>
  SO3<T> cast() const {
    SO3<T> r;
    r.setQuaternion(q_.template cast<T>());
    return r;
  }

  SO3 operator*(const SO3& other) const {
    SO3 r = *this;
    r *= other;
    return r;
  }
  SO3& operator*=(const SO3& other) {
    using std::abs;
    q_ = q_ * other.q_;
    // Products drift off the unit sphere by ~1 ulp each; renormalise before it matters.
    if (abs(q_.squaredNorm() - Scalar(1)) > Constants::epsilon()) q_.normalize();
    return *this;
  }
  template <class Derived>
  Point operator*(const Eigen::MatrixBase<Derived>& p) const {
    static_assert(Derived::RowsAtCompileTime == 3 && Derived::ColsAtCompileTime == 1, "SO3 acts on 3-vectors");
    return q_._transformVector(Point(p));
  }

  // Rotation angle of this^-1 * other <= tol.
  bool isApprox(const SO3& other, Scalar tol = Scalar(1e3) * Constants::epsilon()) const {
    return (inverse() * other).angle() <= tol;
  }

  // ---- Jacobians (Barfoot, "State Estimation for Robotics", sec. 7.1.5; Forster et al. 2017, eq. 8-9).
  // Left Jacobian: exp(phi + d) = exp(Jl(phi) d) exp(phi) + O(d^2),
  //   Jl = I + (1 - cos t)/t^2 [phi]x + (t - sin t)/t^3 [phi]x^2,   t = |phi|.
  static Transformation leftJacobian(const Tangent& phi) {
    using std::sqrt;
    const Scalar t = sqrt(phi.squaredNorm());
    const Transformation P = hat(phi);
    return Transformation::Identity() + lie::oneMinusCosOverTheta2(t) * P + lie::thetaMinusSinOverTheta3(t) * P * P;
  }
  // Jl^-1 = I - 1/2 [phi]x + (1/t^2 - (1 + cos t) / (2 t sin t)) [phi]x^2; so log(exp(d) R) =
  // log(R) + Jl^-1(log R) d + O(d^2). Finite up to t = pi.
  static Transformation leftJacobianInverse(const Tangent& phi) {
    using std::sqrt;
    const Scalar t = sqrt(phi.squaredNorm());
    const Transformation P = hat(phi);
    return Transformation::Identity() - P / Scalar(2) + lie::invLeftJacobianCoeff(t) * P * P;
  }
  // Right Jacobian: exp(phi + d) = exp(phi) exp(Jr(phi) d) + O(d^2); Jr(phi) = Jl(-phi) = Jl(phi)^T.
  // With Jr^-1: log(R exp(d)) = log(R) + Jr^-1(log R) d (Forster's preintegration uses these two).
  static Transformation rightJacobian(const Tangent& phi) { return leftJacobian(-phi); }
  static Transformation rightJacobianInverse(const Tangent& phi) { return leftJacobianInverse(-phi); }

  // d(exp(d) R p)/dd at d = 0 = -[R p]x   (left perturbation, the optimiser's).
  Transformation dActionDLeft(const Point& p) const { return -hat(*this * p); }
  // d(R exp(d) p)/dd at d = 0 = -R [p]x   (right perturbation).
  Transformation dActionDRight(const Point& p) const { return -matrix() * hat(p); }

  // Uniform (Haar) random rotation: a normalised 4D Gaussian.
  template <class Generator>
  static SO3 sampleUniform(Generator& gen) {
    std::normal_distribution<double> n(0.0, 1.0);
    QuaternionType q;
    do {
      q = QuaternionType(Scalar(n(gen)), Scalar(n(gen)), Scalar(n(gen)), Scalar(n(gen)));
    } while (q.squaredNorm() < Scalar(1e-4));
    SO3 r;
    r.setQuaternion(q);
    return r;
  }
  static SO3 rotX(Scalar a) { return exp(Tangent(a, Scalar(0), Scalar(0))); }
  static SO3 rotY(Scalar a) { return exp(Tangent(Scalar(0), a, Scalar(0))); }
  static SO3 rotZ(Scalar a) { return exp(Tangent(Scalar(0), Scalar(0), a)); }

 private:
  static SO3 fromQuaternionUnchecked(const QuaternionType& q) {
    SO3 r;
    r.q_ = q;
    return r;
  }
  static std::string str(Scalar v) {
    std::ostringstream os;
    os << v;
    return os.str();
  }

  QuaternionType q_;
};

using SO3d = SO3<double>;
using SO3f = SO3<float>;

}  // namespace rsvio
