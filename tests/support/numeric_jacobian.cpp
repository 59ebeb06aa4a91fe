// Comparison half of the shared numeric-Jacobian helper (numeric_jacobian.h has the contract).
#include "support/numeric_jacobian.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace rsvio {
namespace test {

namespace {

const Eigen::IOFormat kFullPrecision(Eigen::FullPrecision, 0, ", ", "\n", "  [", "]");

::testing::AssertionResult compare(const char* analytic_expr, const char* numeric_expr, const Eigen::MatrixXd& a,
                                   const Eigen::MatrixXd& n, double rel_tol, double abs_tol) {
  std::ostringstream os;
  const auto describe = [&]() {
    os << "\n" << analytic_expr << " (analytic, " << a.rows() << "x" << a.cols() << "):\n" << a.format(kFullPrecision)
       << "\n" << numeric_expr << " (numeric, " << n.rows() << "x" << n.cols() << "):\n" << n.format(kFullPrecision);
  };
  if (a.rows() != n.rows() || a.cols() != n.cols()) {
    os << "Jacobian sizes differ";
    describe();
    return ::testing::AssertionFailure() << os.str();
  }
  int worst_r = -1, worst_c = -1;
  double worst_excess = 0.0;  // |a - n| / (abs_tol + rel_tol * max(|a|, |n|)); > 1 fails
  bool has_nan = false;
  for (int c = 0; c < a.cols(); ++c) {
    for (int r = 0; r < a.rows(); ++r) {
      const double x = a(r, c), y = n(r, c);
      if (!std::isfinite(x) || !std::isfinite(y)) {
        has_nan = true;
        continue;
      }
      const double allowed = abs_tol + rel_tol * std::max(std::abs(x), std::abs(y));
      const double excess = std::abs(x - y) / allowed;
      if (excess > worst_excess) {
        worst_excess = excess;
        worst_r = r;
        worst_c = c;
      }
    }
  }
  if (!has_nan && worst_excess <= 1.0) return ::testing::AssertionSuccess();
  const Eigen::MatrixXd diff = a - n;
  if (has_nan) os << "Jacobian has non-finite entries. ";
  if (worst_r >= 0 && worst_excess > 1.0)
    os << "Jacobians differ: worst entry (" << worst_r << ", " << worst_c << ") analytic "
       << a(worst_r, worst_c) << " numeric " << n(worst_r, worst_c) << ", |diff| "
       << std::abs(diff(worst_r, worst_c)) << " > allowed " << abs_tol << " + " << rel_tol << " * max(|a|, |n|)";
  os << "\n|analytic - numeric| (Frobenius norm) = " << diff.norm() << ", |numeric| = " << n.norm();
  describe();
  os << "\nanalytic - numeric:\n" << diff.format(kFullPrecision);
  return ::testing::AssertionFailure() << os.str();
}

}  // namespace

::testing::AssertionResult jacobianNear(const Eigen::MatrixXd& analytic, const Eigen::MatrixXd& numeric,
                                        double rel_tol, double abs_tol) {
  return compare("analytic", "numeric", analytic, numeric, rel_tol, abs_tol);
}

::testing::AssertionResult jacobianNearFormat(const char* analytic_expr, const char* numeric_expr,
                                              const Eigen::MatrixXd& analytic, const Eigen::MatrixXd& numeric,
                                              double rel_tol, double abs_tol) {
  return compare(analytic_expr, numeric_expr, analytic, numeric, rel_tol, abs_tol);
}

}  // namespace test
}  // namespace rsvio
