// Sim3<S>: similarity transformations, acting as [sR t; 0 1], p -> s R p + t. Invariant: rxso3_ is a
// valid RxSO3 (scale > 0, unit quaternion), translation_ any finite 3-vector.
// Tangent (upsilon; omega; sigma), as in Sophus:
//   exp = [e^sigma exp(omega), W(omega, sigma) upsilon; 0 1],
//   W = integral_0^1 exp(s ([omega]x + sigma I)) ds = A I + B [omega]x + C [omega]x^2  (calcW below).
// Conventions of the whole module (left perturbation, Adj, frames): lie.h.
#pragma once

#include <Eigen/LU>

#include "rsvio/lie/rxso3.h"

namespace rsvio {

template <class Scalar_>
class Sim3 {
 public:
  using Scalar = Scalar_;
  static constexpr int DoF = 7;
  static constexpr int num_parameters = 8;  // quaternion (x, y, z, w), scale, translation
  using Tangent = Eigen::Matrix<Scalar, 7, 1>;
  using Point = Eigen::Matrix<Scalar, 3, 1>;
  using Vector3 = Eigen::Matrix<Scalar, 3, 1>;
  using Matrix3 = Eigen::Matrix<Scalar, 3, 3>;
  using Transformation = Eigen::Matrix<Scalar, 4, 4>;
  using Adjoint = Eigen::Matrix<Scalar, 7, 7>;
  using QuaternionType = Eigen::Quaternion<Scalar>;
  using SO3Type = SO3<Scalar>;
  using RxSO3Type = RxSO3<Scalar>;

  Sim3() : translation_(Vector3::Zero()) {}
  Sim3(const RxSO3Type& sR, const Vector3& t) : rxso3_(sR), translation_(t) {}
  // From the 3x3 block sR (see RxSO3's constructor) and t.
  Sim3(const Matrix3& sR, const Vector3& t) : rxso3_(sR), translation_(t) {}
  Sim3(Scalar scale, const QuaternionType& q, const Vector3& t) : rxso3_(scale, q), translation_(t) {}
  // Throws rsvio::Error unless the last row is (0 0 0 1) and the block is a positive scaled rotation.
  explicit Sim3(const Transformation& T)
      : rxso3_(Matrix3(T.template topLeftCorner<3, 3>())), translation_(T.template topRightCorner<3, 1>()) {
    if (!(T.template bottomRows<1>().isApprox(Eigen::Matrix<Scalar, 1, 4>(Scalar(0), Scalar(0), Scalar(0), Scalar(1)))))
      throw Error("Sim3: last row of the 4x4 matrix is not (0 0 0 1)");
  }

  static Sim3 Identity() { return Sim3(); }

  static Sim3 exp(const Tangent& a) {
    const RxSO3Type sR = RxSO3Type::exp(a.template tail<4>());
    return Sim3(sR, calcW(a.template segment<3>(3), a[6]) * a.template head<3>());
  }
  Tangent log() const {
    Tangent a;
    const Eigen::Matrix<Scalar, 4, 1> r = rxso3_.log();
    a.template tail<4>() = r;
    // W is invertible on the principal range (its eigenvalues (e^z - 1)/z vanish only at z = 2 pi i k).
    a.template head<3>() = calcW(r.template head<3>(), r[3]).partialPivLu().solve(translation_);
    return a;
  }

  // hat(a) = [[omega]x + sigma I, upsilon; 0 0].
  static Transformation hat(const Tangent& a) {
    Transformation X = Transformation::Zero();
    X.template topLeftCorner<3, 3>() = RxSO3Type::hat(a.template tail<4>());
    X.template topRightCorner<3, 1>() = a.template head<3>();
    return X;
  }
  static Tangent vee(const Transformation& X) {
    Tangent a;
    a << X.template topRightCorner<3, 1>(), RxSO3Type::vee(X.template topLeftCorner<3, 3>());
    return a;
  }

  Sim3 inverse() const {
    const RxSO3Type inv = rxso3_.inverse();
    return Sim3(inv, -(inv * translation_));
  }
  // T exp(d) = exp(Adj d) T (paper eq. 26) with
  //   Adj = [sR, [t]x R, -t; 0, R, 0; 0, 0, 1]   for d = (upsilon; omega; sigma).
  Adjoint Adj() const {
    const Matrix3 R = rxso3_.rotationMatrix();
    Adjoint A = Adjoint::Zero();
    A.template block<3, 3>(0, 0) = rxso3_.scale() * R;
    A.template block<3, 3>(0, 3) = SO3Type::hat(translation_) * R;
    A.template block<3, 1>(0, 6) = -translation_;
    A.template block<3, 3>(3, 3) = R;
    A(6, 6) = Scalar(1);
    return A;
  }

  Transformation matrix() const {
    Transformation T = Transformation::Identity();
    T.template topLeftCorner<3, 3>() = rxso3_.matrix();
    T.template topRightCorner<3, 1>() = translation_;
    return T;
  }
  Eigen::Matrix<Scalar, 3, 4> matrix3x4() const { return matrix().template topRows<3>(); }
  Matrix3 rotationMatrix() const { return rxso3_.rotationMatrix(); }
  const RxSO3Type& rxso3() const { return rxso3_; }
  RxSO3Type& rxso3() { return rxso3_; }
  const SO3Type& so3() const { return rxso3_.so3(); }
  Scalar scale() const { return rxso3_.scale(); }
  void setScale(Scalar s) { rxso3_.setScale(s); }
  const Vector3& translation() const { return translation_; }
  Vector3& translation() { return translation_; }
  const QuaternionType& unit_quaternion() const { return rxso3_.unit_quaternion(); }
  void setQuaternion(const QuaternionType& q) { rxso3_.setQuaternion(q); }
  // (qx, qy, qz, qw, scale, tx, ty, tz).
  Eigen::Matrix<Scalar, 8, 1> params() const {
    Eigen::Matrix<Scalar, 8, 1> p;
    p << rxso3_.params(), translation_;
    return p;
  }

  template <class T>
  Sim3<T> cast() const {
    return Sim3<T>(rxso3_.template cast<T>(), translation_.template cast<T>());
  }

  Sim3 operator*(const Sim3& o) const { return Sim3(rxso3_ * o.rxso3_, rxso3_ * o.translation_ + translation_); }
  Sim3& operator*=(const Sim3& o) {
    *this = *this * o;
    return *this;
  }
  template <class Derived>
  Point operator*(const Eigen::MatrixBase<Derived>& p) const {
    static_assert(Derived::RowsAtCompileTime == 3 && Derived::ColsAtCompileTime == 1, "Sim3 acts on 3-vectors");
    return rxso3_ * p + translation_;
  }

  // RxSO3 parts within tol and translations within tol * max(1, |t|, |t'|).
  bool isApprox(const Sim3& other, Scalar tol = Scalar(1e3) * SO3Type::Constants::epsilon()) const {
    using std::max;
    return rxso3_.isApprox(other.rxso3_, tol) &&
           (translation_ - other.translation_).norm() <=
               tol * max(Scalar(1), max(translation_.norm(), other.translation_.norm()));
  }

  // d(exp(d) T p)/dd at d = 0 = [I, -[T p]x, T p]  (3x7). d(T p)/dp = s R.
  Eigen::Matrix<Scalar, 3, 7> dActionDLeft(const Point& p) const {
    const Point y = *this * p;
    Eigen::Matrix<Scalar, 3, 7> J;
    J.template leftCols<3>().setIdentity();
    J.template block<3, 3>(0, 3) = -SO3Type::hat(y);
    J.col(6) = y;
    return J;
  }

  // W(omega, sigma) = integral_0^1 e^{sigma s} exp(s [omega]x) ds = A I + B [omega]x + C [omega]x^2 with
  //   A = (e^sigma - 1)/sigma, B = Im g(z)/theta, C = (A - Re g(z))/theta^2,
  //   g(z) = (e^z - 1)/z, z = sigma + i theta, theta = |omega|.
  // For |z| < 1 all three come from g's power series sum z^n/(n+1)! in exact polynomial form (no
  // division by theta or sigma); otherwise from the closed forms, with the theta -> 0 limits
  // B = int s e^{sigma s} ds, C = int s^2/2 e^{sigma s} ds when theta is below epsilon.
  static Matrix3 calcW(const Vector3& omega, Scalar sigma) {
    using std::cos;
    using std::exp;
    using std::expm1;
    using std::sin;
    using std::sqrt;
    const Scalar t2 = omega.squaredNorm();
    const Scalar t = sqrt(t2);
    Scalar A, B, C;
    if (sigma * sigma + t2 < Scalar(1)) {
      // z^n = p_n + i t Q_n, sigma^n - p_n = t^2 P_n; A = sum sigma^n/(n+1)!, B = sum Q_n/(n+1)!,
      // C = sum P_n/(n+1)!.
      Scalar p(1), Q(0), P(0), sn(1), inv_fact(1);
      A = B = C = Scalar(0);
      for (int n = 0; n < 20; ++n) {
        inv_fact /= Scalar(n + 1);
        A += sn * inv_fact;
        B += Q * inv_fact;
        C += P * inv_fact;
        const Scalar p_next = sigma * p - t2 * Q;
        const Scalar Q_next = sigma * Q + p;
        P = sigma * P + Q;
        p = p_next;
        Q = Q_next;
        sn *= sigma;
      }
    } else {
      using std::abs;
      const Scalar es = exp(sigma);
      A = abs(sigma) < SO3Type::Constants::epsilon() ? Scalar(1) + sigma / Scalar(2) : expm1(sigma) / sigma;
      if (t < SO3Type::Constants::epsilon()) {  // here |sigma| >= 1, so these are well conditioned
        const Scalar s2 = sigma * sigma;
        B = (es * (sigma - Scalar(1)) + Scalar(1)) / s2;
        C = (es * (s2 - Scalar(2) * sigma + Scalar(2)) - Scalar(2)) / (Scalar(2) * s2 * sigma);
      } else {
        const Scalar st = sin(t), ct = cos(t), den = sigma * sigma + t2;
        B = (es * (sigma * st - t * ct) + t) / (t * den);
        C = (A - (es * (sigma * ct + t * st) - sigma) / den) / t2;
      }
    }
    const Matrix3 Wx = SO3Type::hat(omega);
    return A * Matrix3::Identity() + B * Wx + C * Wx * Wx;
  }

  // Uniform rotation, log-scale uniform in [-1, 1], translation uniform in [-1, 1]^3.
  template <class Generator>
  static Sim3 sampleUniform(Generator& gen) {
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const RxSO3Type sR = RxSO3Type::sampleUniform(gen);
    return Sim3(sR, Vector3(Scalar(u(gen)), Scalar(u(gen)), Scalar(u(gen))));
  }

 private:
  RxSO3Type rxso3_;
  Vector3 translation_;
};

using Sim3d = Sim3<double>;
using Sim3f = Sim3<float>;

}  // namespace rsvio
