// SE3<S>: rigid-body transformations, acting as [R t; 0 1] (paper eq. 1). Invariant: so3_ is a valid
// SO3 (unit quaternion), translation_ is any finite 3-vector. T_a_b * p_b = R p_b + t = p_a.
// Tangent xi = (upsilon; omega): translation part first, rotation last (paper sec. III);
// exp(xi) = [exp(omega), Jl(omega) upsilon; 0 1] with Jl SO(3)'s left Jacobian.
// Conventions of the whole module (left perturbation, Adj, frames): lie.h.
#pragma once

#include "rsvio/lie/so3.h"

namespace rsvio {

template <class Scalar_>
class SE3 {
 public:
  using Scalar = Scalar_;
  static constexpr int DoF = 6;
  static constexpr int num_parameters = 7;  // quaternion (x, y, z, w), translation
  using Tangent = Eigen::Matrix<Scalar, 6, 1>;
  using Point = Eigen::Matrix<Scalar, 3, 1>;
  using Vector3 = Eigen::Matrix<Scalar, 3, 1>;
  using Matrix3 = Eigen::Matrix<Scalar, 3, 3>;
  using Transformation = Eigen::Matrix<Scalar, 4, 4>;
  using Adjoint = Eigen::Matrix<Scalar, 6, 6>;
  using Matrix6 = Eigen::Matrix<Scalar, 6, 6>;
  using QuaternionType = Eigen::Quaternion<Scalar>;
  using SO3Type = SO3<Scalar>;

  SE3() : translation_(Vector3::Zero()) {}
  SE3(const SO3Type& R, const Vector3& t) : so3_(R), translation_(t) {}
  // R must be a rotation, q of unit norm (checked as in SO3's constructors; throw rsvio::Error).
  SE3(const Matrix3& R, const Vector3& t) : so3_(R), translation_(t) {}
  SE3(const QuaternionType& q, const Vector3& t) : so3_(q), translation_(t) {}
  // Throws rsvio::Error unless the last row is (0 0 0 1) and the block is a rotation.
  explicit SE3(const Transformation& T) : so3_(Matrix3(T.template topLeftCorner<3, 3>())), translation_(T.template topRightCorner<3, 1>()) {
    if (!(T.template bottomRows<1>().isApprox(Eigen::Matrix<Scalar, 1, 4>(Scalar(0), Scalar(0), Scalar(0), Scalar(1)))))
      throw Error("SE3: last row of the 4x4 matrix is not (0 0 0 1)");
  }

  static SE3 Identity() { return SE3(); }
  static SE3 trans(const Vector3& t) { return SE3(SO3Type(), t); }

  // exp(xi) = (exp(omega), Jl(omega) upsilon).
  static SE3 exp(const Tangent& xi) {
    const Vector3 omega = xi.template tail<3>();
    return SE3(SO3Type::exp(omega), SO3Type::leftJacobian(omega) * xi.template head<3>());
  }
  // (Jl(omega)^-1 t; omega), omega = log(R) with angle in [0, pi].
  Tangent log() const {
    Tangent xi;
    const Vector3 omega = so3_.log();
    xi.template head<3>() = SO3Type::leftJacobianInverse(omega) * translation_;
    xi.template tail<3>() = omega;
    return xi;
  }

  // hat(xi) = [[omega]x upsilon; 0 0].
  static Transformation hat(const Tangent& xi) {
    Transformation X = Transformation::Zero();
    X.template topLeftCorner<3, 3>() = SO3Type::hat(xi.template tail<3>());
    X.template topRightCorner<3, 1>() = xi.template head<3>();
    return X;
  }
  static Tangent vee(const Transformation& X) {
    Tangent xi;
    xi.template head<3>() = X.template topRightCorner<3, 1>();
    xi.template tail<3>() = SO3Type::vee(X.template topLeftCorner<3, 3>());
    return xi;
  }

  SE3 inverse() const {
    const SO3Type R_inv = so3_.inverse();
    return SE3(R_inv, -(R_inv * translation_));
  }
  // T exp(d) = exp(Adj d) T (paper eq. 26): Adj = [R, [t]x R; 0, R] for d = (upsilon; omega).
  Adjoint Adj() const {
    const Matrix3 R = so3_.matrix();
    Adjoint A;
    A.template topLeftCorner<3, 3>() = R;
    A.template topRightCorner<3, 3>() = SO3Type::hat(translation_) * R;
    A.template bottomLeftCorner<3, 3>().setZero();
    A.template bottomRightCorner<3, 3>() = R;
    return A;
  }

  Transformation matrix() const {
    Transformation T = Transformation::Identity();
    T.template topLeftCorner<3, 3>() = so3_.matrix();
    T.template topRightCorner<3, 1>() = translation_;
    return T;
  }
  Eigen::Matrix<Scalar, 3, 4> matrix3x4() const { return matrix().template topRows<3>(); }
  Matrix3 rotationMatrix() const { return so3_.matrix(); }
  const SO3Type& so3() const { return so3_; }
  SO3Type& so3() { return so3_; }
  const Vector3& translation() const { return translation_; }
  Vector3& translation() { return translation_; }
  const QuaternionType& unit_quaternion() const { return so3_.unit_quaternion(); }
  void setQuaternion(const QuaternionType& q) { so3_.setQuaternion(q); }  // normalises, see SO3
  void setRotationMatrix(const Matrix3& R) { so3_ = SO3Type(R); }
  // (qx, qy, qz, qw, tx, ty, tz).
  Eigen::Matrix<Scalar, 7, 1> params() const {
    Eigen::Matrix<Scalar, 7, 1> p;
    p << so3_.params(), translation_;
    return p;
  }

  template <class T>
  SE3<T> cast() const {
    return SE3<T>(so3_.template cast<T>(), translation_.template cast<T>());
  }

  // T_a_b * T_b_c = T_a_c.
  SE3 operator*(const SE3& other) const { return SE3(so3_ * other.so3_, so3_ * other.translation_ + translation_); }
  SE3& operator*=(const SE3& other) {
    *this = *this * other;
    return *this;
  }
  template <class Derived>
  Point operator*(const Eigen::MatrixBase<Derived>& p) const {
    static_assert(Derived::RowsAtCompileTime == 3 && Derived::ColsAtCompileTime == 1, "SE3 acts on 3-vectors");
    return so3_ * p + translation_;
  }

  // Rotations within tol (angle) and translations within tol * max(1, |t|, |t'|).
  bool isApprox(const SE3& other, Scalar tol = Scalar(1e3) * SO3Type::Constants::epsilon()) const {
    using std::max;
    return so3_.isApprox(other.so3_, tol) &&
           (translation_ - other.translation_).norm() <=
               tol * max(Scalar(1), max(translation_.norm(), other.translation_.norm()));
  }

  // ---- Jacobians (Barfoot, "State Estimation for Robotics", sec. 7.1.5, with xi = (rho; phi)).
  // Left Jacobian: exp(xi + d) = exp(Jl(xi) d) exp(xi) + O(d^2),
  //   Jl(xi) = [J, Q; 0, J],   J = SO3::leftJacobian(omega),
  //   Q = 1/2 [u] + c (W U + U W + W U W) + d (W W U + U W W - 3 W U W) + e (W U W W + W W U W),
  //   U = [upsilon]x, W = [omega]x, c = (t - sin t)/t^3, d = (t^2 + 2 cos t - 2)/(2 t^4),
  //   e = (2 t - 3 sin t + t cos t)/(2 t^5), t = |omega|.
  // Rolling shutter (paper eq. 6): T(t) = exp(xi t) T0 with left perturbation of the output gives
  //   d T(t) / d xi = t * Jl(t xi), so d(T(t) p)/d xi = dActionDLeft-of-T(t)(p) * t * Jl(t xi).
  static Matrix6 leftJacobian(const Tangent& xi) {
    const Vector3 omega = xi.template tail<3>();
    const Matrix3 J = SO3Type::leftJacobian(omega);
    Matrix6 Jl;
    Jl.template topLeftCorner<3, 3>() = J;
    Jl.template topRightCorner<3, 3>() = calcQ(xi);
    Jl.template bottomLeftCorner<3, 3>().setZero();
    Jl.template bottomRightCorner<3, 3>() = J;
    return Jl;
  }
  // Jl^-1 = [J^-1, -J^-1 Q J^-1; 0, J^-1]; log(exp(d) T) = log(T) + Jl^-1(log T) d + O(d^2).
  static Matrix6 leftJacobianInverse(const Tangent& xi) {
    const Matrix3 J_inv = SO3Type::leftJacobianInverse(xi.template tail<3>());
    Matrix6 Jl_inv;
    Jl_inv.template topLeftCorner<3, 3>() = J_inv;
    Jl_inv.template topRightCorner<3, 3>() = -J_inv * calcQ(xi) * J_inv;
    Jl_inv.template bottomLeftCorner<3, 3>().setZero();
    Jl_inv.template bottomRightCorner<3, 3>() = J_inv;
    return Jl_inv;
  }
  // exp(xi + d) = exp(xi) exp(Jr(xi) d); Jr(xi) = Jl(-xi). log(T exp(d)) = log(T) + Jr^-1(log T) d.
  static Matrix6 rightJacobian(const Tangent& xi) { return leftJacobian(-xi); }
  static Matrix6 rightJacobianInverse(const Tangent& xi) { return leftJacobianInverse(-xi); }

  // d(exp(d) T p)/dd at d = 0 = [I, -[T p]x]  (3x6; the optimiser's left perturbation).
  Eigen::Matrix<Scalar, 3, 6> dActionDLeft(const Point& p) const {
    Eigen::Matrix<Scalar, 3, 6> J;
    J.template leftCols<3>().setIdentity();
    J.template rightCols<3>() = -SO3Type::hat(*this * p);
    return J;
  }
  // d(T exp(d) p)/dd at d = 0 = [R, -R [p]x]  (3x6, right perturbation). d(T p)/dp = R.
  Eigen::Matrix<Scalar, 3, 6> dActionDRight(const Point& p) const {
    const Matrix3 R = so3_.matrix();
    Eigen::Matrix<Scalar, 3, 6> J;
    J.template leftCols<3>() = R;
    J.template rightCols<3>() = -R * SO3Type::hat(p);
    return J;
  }

  // Uniform rotation, translation uniform in [-1, 1]^3.
  template <class Generator>
  static SE3 sampleUniform(Generator& gen) {
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const SO3Type R = SO3Type::sampleUniform(gen);
    return SE3(R, Vector3(Scalar(u(gen)), Scalar(u(gen)), Scalar(u(gen))));
  }

 private:
  static Matrix3 calcQ(const Tangent& xi) {
    using std::sqrt;
    const Vector3 omega = xi.template tail<3>();
    const Scalar t = sqrt(omega.squaredNorm());
    const Matrix3 U = SO3Type::hat(xi.template head<3>());
    const Matrix3 W = SO3Type::hat(omega);
    const Matrix3 WU = W * U, UW = U * W, WUW = WU * W;
    return U / Scalar(2) + lie::thetaMinusSinOverTheta3(t) * (WU + UW + WUW) +
           lie::se3QCoeff2(t) * (W * WU + UW * W - Scalar(3) * WUW) + lie::se3QCoeff3(t) * (WUW * W + W * WUW);
  }

  SO3Type so3_;
  Vector3 translation_;
};

using SE3d = SE3<double>;
using SE3f = SE3<float>;

}  // namespace rsvio
