// solver.dense: Cholesky on the dense normal equations H x = b (Eigen LDLT or LLT).
// A system that is not positive definite (a zero or negative pivot, relative to the largest) is
// refused with a message instead of returning a meaningless step.
#include <Eigen/Cholesky>
#include <chrono>
#include <memory>
#include <sstream>
#include <string>

#include "rsvio/interfaces/solver.h"
#include "rsvio/plugin/plugin_api.h"

namespace rsvio {
namespace {

const char* kName = "solver.dense";

class DenseSolver : public SolverBackend {
 public:
  explicit DenseSolver(const Params& p)
      : use_llt_(p.getString("method") == "llt"), min_pivot_ratio_(p.getDouble("min_pivot_ratio")) {}

  bool solveDense(const Eigen::MatrixXd& H, const Eigen::VectorXd& b, Eigen::VectorXd& x,
                  SolverStats* stats) override {
    const auto t0 = std::chrono::steady_clock::now();
    std::string msg;
    const bool ok = solve(H, b, x, msg);
    if (stats) {
      stats->ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      stats->message = msg;
    }
    return ok;
  }

 private:
  bool solve(const Eigen::MatrixXd& H, const Eigen::VectorXd& b, Eigen::VectorXd& x, std::string& msg) const {
    std::ostringstream os;
    os << kName << ": ";
    if (H.rows() != H.cols() || H.rows() != b.size()) {
      os << "size mismatch: H is " << H.rows() << "x" << H.cols() << ", b has " << b.size() << " rows";
      msg = os.str();
      return false;
    }
    if (H.rows() == 0) {
      x.resize(0);
      return true;
    }
    if (!H.allFinite() || !b.allFinite()) {
      msg = os.str() + "H or b holds NaN or inf";
      return false;
    }
    if (use_llt_) {
      Eigen::LLT<Eigen::MatrixXd> llt(H);
      if (llt.info() != Eigen::Success) {
        msg = os.str() + "H is not positive definite (LLT failed)";
        return false;
      }
      const Eigen::VectorXd d = llt.matrixLLT().diagonal().array().square();
      if (!pivotsOk(d, os, msg)) return false;
      x = llt.solve(b);
    } else {
      Eigen::LDLT<Eigen::MatrixXd> ldlt(H);
      if (ldlt.info() != Eigen::Success) {
        msg = os.str() + "LDLT failed";
        return false;
      }
      if (!pivotsOk(ldlt.vectorD(), os, msg)) return false;
      x = ldlt.solve(b);
    }
    if (!x.allFinite()) {
      msg = os.str() + "the solution is not finite";
      return false;
    }
    return true;
  }

  // Positive definite within the numerical reach of double: every pivot > ratio * largest pivot.
  bool pivotsOk(const Eigen::VectorXd& d, std::ostringstream& os, std::string& msg) const {
    const double dmax = d.cwiseAbs().maxCoeff();
    Eigen::Index i_min = 0;
    const double dmin = d.minCoeff(&i_min);
    if (!(dmax > 0.0) || !(dmin > min_pivot_ratio_ * dmax)) {
      os << "H is not positive definite (pivot " << i_min << " = " << dmin << ", largest " << dmax
         << ", min_pivot_ratio " << min_pivot_ratio_ << ")";
      msg = os.str();
      return false;
    }
    return true;
  }

  bool use_llt_;
  double min_pivot_ratio_;
};

ParamTable denseParams() {
  return {paramEnum("method", "ldlt", {"ldlt", "llt"}, "Cholesky variant: ldlt (pivoting) or llt"),
          paramDouble("min_pivot_ratio", 1e-14, 0.0, 1.0, "",
                      "H is refused as not positive definite when a pivot <= this times the largest")};
}

void registerAll(PluginRegistrar& r) {
  r.add<SolverBackend>({kName, PluginKind::Solver, "1.0.0",
                        "Dense Cholesky (Eigen LDLT or LLT) on the normal equations", denseParams(), ""},
                       [](const Params& p) { return std::make_unique<DenseSolver>(p); });
}

}  // namespace
}  // namespace rsvio

RSVIO_PLUGIN_ENTRY(rsvio::registerAll)
