// Numerics shared by the Lie groups: per-scalar tolerances and the coefficient functions of SO(3)'s
// exponential, its Jacobians and SE(3)'s Q matrix. Every coefficient is a smooth even function of the
// angle theta >= 0 whose closed form either divides 0 by 0 at theta = 0 or loses digits to
// cancellation for small theta; below a threshold each one is summed from its Taylor series instead.
// The thresholds and term counts are chosen so that series and closed form agree to a few ulps at the
// switch (tests/framework/lie/so3_test.cpp checks the continuity there).
#pragma once

#include <Eigen/Core>
#include <cmath>

namespace rsvio {
namespace lie {

template <class Scalar>
struct Constants;

template <>
struct Constants<double> {
  // Below this an angle (or a quaternion's vector norm) counts as zero where a division would blow up.
  static constexpr double epsilon() { return 1e-10; }
  // Series branch of the coefficients b..e below this angle (10 terms: error < 1e-20 at theta = 1).
  static constexpr double seriesAngle() { return 1.0; }
  // Series branch of f (the Jl^-1 coefficient) below this angle (7 terms: error < 3e-16 at 0.5).
  static constexpr double invSeriesAngle() { return 0.5; }
  // Accepted deviation of |q|^2 from 1 and of R^T R from I in constructors (input from files has
  // ~1e-9 precision); the stored value is renormalised exactly.
  static constexpr double unitTolerance() { return 1e-6; }
};

template <>
struct Constants<float> {
  static constexpr float epsilon() { return 1e-5f; }
  static constexpr float seriesAngle() { return 1.0f; }
  static constexpr float invSeriesAngle() { return 1.0f; }
  static constexpr float unitTolerance() { return 1e-4f; }
};

template <class S>
constexpr S pi() {
  return S(3.141592653589793238462643383279502884L);
}

// Skew-symmetric matrix [w]x with [w]x v = w x v.
template <class S>
Eigen::Matrix<S, 3, 3> skew(const Eigen::Matrix<S, 3, 1>& w) {
  Eigen::Matrix<S, 3, 3> W;
  W << S(0), -w.z(), w.y(),  //
      w.z(), S(0), -w.x(),   //
      -w.y(), w.x(), S(0);
  return W;
}

namespace detail {

// Sum_{k=0}^{n-1} (-1)^k theta^{2k} / (2k + m)!  (m! times the series of a coefficient whose k-th
// Taylor term is (-1)^k theta^{2k} / (2k + m)!).
template <class S>
S alternatingFactorialSeries(S theta2, int m, int n = 10) {
  S term(1);
  for (int i = 2; i <= m; ++i) term /= S(i);
  S sum(0);
  for (int k = 0; k < n; ++k) {
    sum += term;
    term *= -theta2 / (S(2 * k + m + 1) * S(2 * k + m + 2));
  }
  return sum;
}

}  // namespace detail

// a(theta) = sin(theta) / theta.
template <class S>
S sinOverTheta(S theta) {
  using std::sin;
  if (theta < Constants<S>::seriesAngle()) return detail::alternatingFactorialSeries(theta * theta, 1);
  return sin(theta) / theta;
}

// b(theta) = (1 - cos(theta)) / theta^2, the coefficient of [w]x in SO(3)'s left Jacobian.
template <class S>
S oneMinusCosOverTheta2(S theta) {
  using std::cos;
  if (theta < Constants<S>::seriesAngle()) return detail::alternatingFactorialSeries(theta * theta, 2);
  return (S(1) - cos(theta)) / (theta * theta);
}

// c(theta) = (theta - sin(theta)) / theta^3, the coefficient of [w]x^2 in SO(3)'s left Jacobian.
template <class S>
S thetaMinusSinOverTheta3(S theta) {
  using std::sin;
  if (theta < Constants<S>::seriesAngle()) return detail::alternatingFactorialSeries(theta * theta, 3);
  return (theta - sin(theta)) / (theta * theta * theta);
}

// d(theta) = (theta^2 + 2 cos(theta) - 2) / (2 theta^4), second coefficient of SE(3)'s Q matrix.
template <class S>
S se3QCoeff2(S theta) {
  using std::cos;
  if (theta < Constants<S>::seriesAngle()) return detail::alternatingFactorialSeries(theta * theta, 4);
  const S t2 = theta * theta;
  return (t2 + S(2) * cos(theta) - S(2)) / (S(2) * t2 * t2);
}

// e(theta) = (2 theta - 3 sin(theta) + theta cos(theta)) / (2 theta^5), third coefficient of Q;
// series sum_k (-1)^k (k + 1) theta^{2k} / (2k + 5)!.
template <class S>
S se3QCoeff3(S theta) {
  using std::cos;
  using std::sin;
  const S t2 = theta * theta;
  if (theta < Constants<S>::seriesAngle()) {
    S term = S(1) / S(120);
    S sum(0);
    for (int k = 0; k < 10; ++k) {
      sum += S(k + 1) * term;
      term *= -t2 / (S(2 * k + 6) * S(2 * k + 7));
    }
    return sum;
  }
  return (S(2) * theta - S(3) * sin(theta) + theta * cos(theta)) / (S(2) * t2 * t2 * theta);
}

// f(theta) = 1/theta^2 - (1 + cos(theta)) / (2 theta sin(theta)) = (1 - (theta/2) cot(theta/2)) / theta^2,
// the coefficient of [w]x^2 in SO(3)'s inverse left Jacobian. Written with cot(theta/2) it stays finite
// at theta = pi (value 1/pi^2); it has a pole at 2 pi, outside the principal range of log.
// Series from x cot x = 1 - sum 2^{2n} |B_2n| x^{2n} / (2n)! (Bernoulli numbers).
template <class S>
S invLeftJacobianCoeff(S theta) {
  using std::tan;
  const S t2 = theta * theta;
  if (theta < Constants<S>::invSeriesAngle()) {
    const S c[7] = {S(1.0 / 12.0),        S(1.0 / 720.0),
                    S(1.0 / 30240.0),     S(1.0 / 1209600.0),
                    S(1.0 / 47900160.0),  S(691.0 / 1307674368000.0),
                    S(1.0 / 74724249600.0)};
    S sum = c[6];
    for (int k = 5; k >= 0; --k) sum = sum * t2 + c[k];
    return sum;
  }
  const S half = theta / S(2);
  return (S(1) - half / tan(half)) / t2;
}

}  // namespace lie
}  // namespace rsvio
