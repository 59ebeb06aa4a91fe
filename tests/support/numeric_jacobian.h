// The shared numeric-Jacobian helper: every analytic derivative in rsvio is tested against it.
//
//   Eigen::MatrixXd numericJacobian(f, x0, plus, dim, eps = 1e-6);          f: X -> vector or scalar
//   Eigen::MatrixXd numericJacobian(f, x0, plus, minus, dim, eps = 1e-6);   f: X -> Y, any Y
//
// Column i is the central difference along the i-th tangent direction e_i of the input,
//   J.col(i) = ( minus(f(plus(x0, +eps e_i)), f(x0)) - minus(f(plus(x0, -eps e_i)), f(x0)) ) / (2 eps),
// so J is the derivative of the output in the chart `minus` around f(x0) w.r.t. the chart `plus`
// around x0. Without `minus` the output is converted to an Eigen::VectorXd (scalars become 1-vectors,
// matrices are flattened column-major) and differenced as a vector. f must return a value (write
// `return Eigen::Vector3d(T * p);`), not an Eigen expression that refers to f's locals.
//
// Ready-made charts (use the one matching the analytic Jacobian's convention):
//   vectorPlus        x + d                          (Eigen vectors, or a scalar with dim = 1)
//   leftPlus<G>       exp(d) * x                     THE optimiser's perturbation (rsvio/lie/lie.h)
//   rightPlus<G>      x * exp(d)                     Forster's IMU preintegration
//   vectorMinus       y - y0
//   leftMinus<G>      log(y * y0^-1)                 group-valued output, left chart
//   rightMinus<G>     log(y0^-1 * y)                 group-valued output, right chart
// For composite states (pose, velocity, biases) write a plus lambda that splits d.
//
// Comparison:
//   jacobianNear(analytic, numeric, rel_tol, abs_tol) -> ::testing::AssertionResult; passes when the
//   sizes match, nothing is NaN and every entry has |a - n| <= abs_tol + rel_tol * max(|a|, |n|).
//   On failure the message holds both matrices, their difference, its norm and the worst entry.
//   EXPECT_JACOBIAN_NEAR(analytic, numeric, tol) / ASSERT_JACOBIAN_NEAR: rel_tol = abs_tol = tol.
//   EXPECT_JACOBIAN_NEAR_TOL(analytic, numeric, rel_tol, abs_tol) for separate tolerances.
// The arguments may be any Eigen expressions of any scalar (float Jacobians are compared in double).
// With eps = 1e-6 in double, numeric Jacobians are good to ~1e-8 relative on smooth functions;
// tol = 1e-6 is the usual choice. For float code use eps ~ 1e-3 and tol ~ 1e-3.
//
// Example (derivative of a transformed point w.r.t. the left pose perturbation):
//   const Eigen::MatrixXd num = numericJacobian([&](const SE3d& T) { return Eigen::Vector3d(T * p); },
//                                               T0, leftPlus<SE3d>, 6);
//   EXPECT_JACOBIAN_NEAR(T0.dActionDLeft(p), num, 1e-6);
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <type_traits>
#include <utility>

namespace rsvio {
namespace test {

namespace detail {

template <class T>
Eigen::VectorXd toVectorXd(const T& y) {
  if constexpr (std::is_arithmetic_v<T>) {
    Eigen::VectorXd v(1);
    v[0] = static_cast<double>(y);
    return v;
  } else {
    const Eigen::MatrixXd m = y.template cast<double>();
    return Eigen::Map<const Eigen::VectorXd>(m.data(), m.size());
  }
}

}  // namespace detail

struct VectorPlus {
  template <class X>
  X operator()(const X& x, const Eigen::VectorXd& d) const {
    if constexpr (std::is_arithmetic_v<X>) {
      return x + static_cast<X>(d[0]);
    } else {
      X r = x;
      r += d.template cast<typename X::Scalar>();
      return r;
    }
  }
};

template <class G>
struct LeftPlus {
  G operator()(const G& x, const Eigen::VectorXd& d) const {
    return G::exp(typename G::Tangent(d.template cast<typename G::Scalar>())) * x;
  }
};

template <class G>
struct RightPlus {
  G operator()(const G& x, const Eigen::VectorXd& d) const {
    return x * G::exp(typename G::Tangent(d.template cast<typename G::Scalar>()));
  }
};

struct VectorMinus {
  template <class Y>
  Eigen::VectorXd operator()(const Y& y, const Y& y0) const {
    return detail::toVectorXd(y) - detail::toVectorXd(y0);
  }
};

template <class G>
struct LeftMinus {
  Eigen::VectorXd operator()(const G& y, const G& y0) const { return detail::toVectorXd((y * y0.inverse()).log()); }
};

template <class G>
struct RightMinus {
  Eigen::VectorXd operator()(const G& y, const G& y0) const { return detail::toVectorXd((y0.inverse() * y).log()); }
};

inline constexpr VectorPlus vectorPlus{};
template <class G>
inline constexpr LeftPlus<G> leftPlus{};
template <class G>
inline constexpr RightPlus<G> rightPlus{};
inline constexpr VectorMinus vectorMinus{};
template <class G>
inline constexpr LeftMinus<G> leftMinus{};
template <class G>
inline constexpr RightMinus<G> rightMinus{};

// f: X -> Y, plus: (X, VectorXd) -> X, minus: (Y, Y) -> VectorXd.
template <class F, class X, class Plus, class Minus, class = std::enable_if_t<!std::is_arithmetic_v<Minus>>>
Eigen::MatrixXd numericJacobian(F&& f, const X& x0, Plus plus, Minus minus, int dim, double eps = 1e-6) {
  const auto y0 = f(x0);
  Eigen::MatrixXd J;
  for (int i = 0; i < dim; ++i) {
    Eigen::VectorXd d = Eigen::VectorXd::Zero(dim);
    d[i] = eps;
    const Eigen::VectorXd up = minus(f(plus(x0, d)), y0);
    const Eigen::VectorXd down = minus(f(plus(x0, Eigen::VectorXd(-d))), y0);
    if (i == 0) J.resize(up.size(), dim);
    J.col(i) = (up - down) / (2.0 * eps);
  }
  return J;
}

// f: X -> Eigen vector/matrix or scalar, differenced as a vector.
template <class F, class X, class Plus>
Eigen::MatrixXd numericJacobian(F&& f, const X& x0, Plus plus, int dim, double eps = 1e-6) {
  return numericJacobian(std::forward<F>(f), x0, plus, vectorMinus, dim, eps);
}

::testing::AssertionResult jacobianNear(const Eigen::MatrixXd& analytic, const Eigen::MatrixXd& numeric,
                                        double rel_tol, double abs_tol);

// gtest predicate-formatter behind the macros; names the expressions in the failure message.
::testing::AssertionResult jacobianNearFormat(const char* analytic_expr, const char* numeric_expr,
                                              const Eigen::MatrixXd& analytic, const Eigen::MatrixXd& numeric,
                                              double rel_tol, double abs_tol);

template <class A, class N>
::testing::AssertionResult jacobianNearFormatAny(const char* analytic_expr, const char* numeric_expr, const char*,
                                                 const char*, const A& analytic, const N& numeric, double rel_tol,
                                                 double abs_tol) {
  const Eigen::MatrixXd a = analytic.template cast<double>();
  const Eigen::MatrixXd n = numeric.template cast<double>();
  return jacobianNearFormat(analytic_expr, numeric_expr, a, n, rel_tol, abs_tol);
}

}  // namespace test
}  // namespace rsvio

#define EXPECT_JACOBIAN_NEAR_TOL(analytic, numeric, rel_tol, abs_tol) \
  EXPECT_PRED_FORMAT4(::rsvio::test::jacobianNearFormatAny, analytic, numeric, rel_tol, abs_tol)
#define ASSERT_JACOBIAN_NEAR_TOL(analytic, numeric, rel_tol, abs_tol) \
  ASSERT_PRED_FORMAT4(::rsvio::test::jacobianNearFormatAny, analytic, numeric, rel_tol, abs_tol)
#define EXPECT_JACOBIAN_NEAR(analytic, numeric, tol) EXPECT_JACOBIAN_NEAR_TOL(analytic, numeric, tol, tol)
#define ASSERT_JACOBIAN_NEAR(analytic, numeric, tol) ASSERT_JACOBIAN_NEAR_TOL(analytic, numeric, tol, tol)
