// RxSO3<S>: the scale-rotation group R+ x SO(3) of the paper's eq. 2, acting on points as s R p (the
// 4x4 form [sR 0; 0 1]); used for T_Wm_Wf, which carries the metric scale and the gravity direction.
// Invariant: stored as (scale_, so3_) with scale_ > 0 and finite, so3_ a valid SO3. (Sophus stores a
// non-unit quaternion with |q|^2 = s; a separate scale keeps tiny and huge scales exact.)
// Tangent (omega; sigma), sigma = log(scale) last, as in Sophus; exp(omega; sigma) = (e^sigma, exp(omega)).
// The group is a direct product, so its exp, log, Jacobians and adjoint split into SO(3) and R parts.
// Conventions of the whole module (left perturbation, Adj, frames): lie.h.
#pragma once

#include "rsvio/lie/so3.h"

namespace rsvio {

template <class Scalar_>
class RxSO3 {
 public:
  using Scalar = Scalar_;
  static constexpr int DoF = 4;
  static constexpr int num_parameters = 5;  // quaternion (x, y, z, w), scale
  using Tangent = Eigen::Matrix<Scalar, 4, 1>;
  using Point = Eigen::Matrix<Scalar, 3, 1>;
  using Vector3 = Eigen::Matrix<Scalar, 3, 1>;
  using Matrix3 = Eigen::Matrix<Scalar, 3, 3>;
  using Transformation = Eigen::Matrix<Scalar, 3, 3>;  // s R
  using Adjoint = Eigen::Matrix<Scalar, 4, 4>;
  using Matrix4 = Eigen::Matrix<Scalar, 4, 4>;
  using QuaternionType = Eigen::Quaternion<Scalar>;
  using SO3Type = SO3<Scalar>;

  RxSO3() : scale_(1) {}
  // Throw rsvio::Error on scale <= 0 (or NaN) and on a non-rotation / non-unit quaternion.
  RxSO3(Scalar scale, const SO3Type& R) : scale_(checkedScale(scale)), so3_(R) {}
  RxSO3(Scalar scale, const Matrix3& R) : scale_(checkedScale(scale)), so3_(R) {}
  RxSO3(Scalar scale, const QuaternionType& q) : scale_(checkedScale(scale)), so3_(q) {}
  // From sR: s = det(sR)^(1/3); throws unless sR / s is a rotation.
  explicit RxSO3(const Transformation& sR) {
    using std::cbrt;
    const Scalar det = sR.determinant();
    scale_ = checkedScale(cbrt(det));
    so3_ = SO3Type(Matrix3(sR / scale_));
  }

  static RxSO3 Identity() { return RxSO3(); }

  static RxSO3 exp(const Tangent& a) {
    using std::exp;
    return RxSO3(exp(a[3]), SO3Type::exp(a.template head<3>()), Unchecked{});
  }
  Tangent log() const {
    using std::log;
    Tangent a;
    a << so3_.log(), log(scale_);
    return a;
  }

  // hat(omega; sigma) = [omega]x + sigma I.
  static Transformation hat(const Tangent& a) {
    return SO3Type::hat(a.template head<3>()) + a[3] * Transformation::Identity();
  }
  // Inverse of hat: sigma = trace / 3, omega from the antisymmetric part.
  static Tangent vee(const Transformation& M) {
    Tangent a;
    a << SO3Type::vee(M), M.trace() / Scalar(3);
    return a;
  }

  RxSO3 inverse() const { return RxSO3(Scalar(1) / scale_, so3_.inverse(), Unchecked{}); }
  // X exp(d) = exp(Adj d) X with Adj = diag(R, 1): scale commutes with everything.
  Adjoint Adj() const {
    Adjoint A = Adjoint::Zero();
    A.template topLeftCorner<3, 3>() = so3_.matrix();
    A(3, 3) = Scalar(1);
    return A;
  }

  Transformation matrix() const { return scale_ * so3_.matrix(); }
  // The paper's eq. 2 form [sR 0; 0 1].
  Matrix4 matrix4() const {
    Matrix4 T = Matrix4::Identity();
    T.template topLeftCorner<3, 3>() = matrix();
    return T;
  }
  Matrix3 rotationMatrix() const { return so3_.matrix(); }
  const SO3Type& so3() const { return so3_; }
  SO3Type& so3() { return so3_; }
  Scalar scale() const { return scale_; }
  void setScale(Scalar s) { scale_ = checkedScale(s); }
  const QuaternionType& unit_quaternion() const { return so3_.unit_quaternion(); }
  void setQuaternion(const QuaternionType& q) { so3_.setQuaternion(q); }
  // (qx, qy, qz, qw, scale).
  Eigen::Matrix<Scalar, 5, 1> params() const {
    Eigen::Matrix<Scalar, 5, 1> p;
    p << so3_.params(), scale_;
    return p;
  }

  template <class T>
  RxSO3<T> cast() const {
    return RxSO3<T>(T(scale_), so3_.template cast<T>());
  }

  RxSO3 operator*(const RxSO3& o) const { return RxSO3(scale_ * o.scale_, so3_ * o.so3_, Unchecked{}); }
  RxSO3& operator*=(const RxSO3& o) {
    *this = *this * o;
    return *this;
  }
  template <class Derived>
  Point operator*(const Eigen::MatrixBase<Derived>& p) const {
    static_assert(Derived::RowsAtCompileTime == 3 && Derived::ColsAtCompileTime == 1, "RxSO3 acts on 3-vectors");
    return scale_ * (so3_ * p);
  }

  // Rotation angle and |log(s) - log(s')| within tol.
  bool isApprox(const RxSO3& other, Scalar tol = Scalar(1e3) * SO3Type::Constants::epsilon()) const {
    using std::abs;
    using std::log;
    return so3_.isApprox(other.so3_, tol) && abs(log(scale_ / other.scale_)) <= tol;
  }

  // ---- Jacobians. Direct product: Jl(omega; sigma) = diag(SO3::leftJacobian(omega), 1), same for the
  // right Jacobian and the inverses.
  static Adjoint leftJacobian(const Tangent& a) { return blockDiag(SO3Type::leftJacobian(a.template head<3>())); }
  static Adjoint leftJacobianInverse(const Tangent& a) {
    return blockDiag(SO3Type::leftJacobianInverse(a.template head<3>()));
  }
  static Adjoint rightJacobian(const Tangent& a) { return blockDiag(SO3Type::rightJacobian(a.template head<3>())); }
  static Adjoint rightJacobianInverse(const Tangent& a) {
    return blockDiag(SO3Type::rightJacobianInverse(a.template head<3>()));
  }

  // d(exp(d) X p)/dd at d = 0 = [-[X p]x, X p]  (3x4; exp(d) = e^sigma exp(omega)). d(X p)/dp = s R.
  Eigen::Matrix<Scalar, 3, 4> dActionDLeft(const Point& p) const {
    const Point y = *this * p;
    Eigen::Matrix<Scalar, 3, 4> J;
    J.template leftCols<3>() = -SO3Type::hat(y);
    J.col(3) = y;
    return J;
  }

  // Uniform rotation, log-scale uniform in [-1, 1].
  template <class Generator>
  static RxSO3 sampleUniform(Generator& gen) {
    using std::exp;
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const SO3Type R = SO3Type::sampleUniform(gen);
    return RxSO3(exp(Scalar(u(gen))), R);
  }

 private:
  struct Unchecked {};
  // Products and exp of finite inputs are positive; a zero/inf scale after underflow is caught by
  // the checked constructors at the edges.
  RxSO3(Scalar s, const SO3Type& R, Unchecked) : scale_(s), so3_(R) {}

  static Scalar checkedScale(Scalar s) {
    using std::isfinite;
    if (!(s > Scalar(0)) || !isfinite(s))
      throw Error("RxSO3: scale must be positive and finite, got " + std::to_string(double(s)));
    return s;
  }
  static Adjoint blockDiag(const Matrix3& J) {
    Adjoint A = Adjoint::Zero();
    A.template topLeftCorner<3, 3>() = J;
    A(3, 3) = Scalar(1);
    return A;
  }

  Scalar scale_;
  SO3Type so3_;
};

using RxSO3d = RxSO3<double>;
using RxSO3f = RxSO3<float>;

}  // namespace rsvio
