// solver.sparse: SuiteSparse CHOLMOD on the full bundle-adjustment system (cameras and points together,
// no Schur step), with the symbolic analysis cached while the sparsity pattern is unchanged.
//
// Why a second solver: the Schur complement costs O(n_points * obs^2 * 8^2) to build and O((8k)^3) to
// factor densely; for large windows (tens of keyframes) the dense camera system dominates, while a
// sparse Cholesky with a fill-reducing ordering (AMD eliminates the 1x1 point blocks first, which is
// the Schur complement done implicitly) keeps only the fill that the co-visibility creates.
// bench/solver_bench.cpp measures where each wins.
//
// solveDense() (the Schur-reduced camera system, small and dense) delegates to Eigen's dense LLT with
// the same pivot-ratio test: converting a dense matrix to CHOLMOD would only add copying, and would
// evict the cached analysis of the full system.
//
// On success SolverStats::message reports the factor kind and the counters
//   "solver.sparse: simplicial LDL', n = 1234, nnz(L) = 56789, flops/nnz(L) = 42, analyses 1, factorizations 3"
// so callers and tests can see that repeated solves with one pattern reuse one analysis.
#include <Eigen/Cholesky>
#include <chrono>
#include <cmath>
#include <memory>
#include <sstream>
#include <string>

#include "cholmod_factor_cache.h"
#include "rsvio/interfaces/solver.h"
#include "rsvio/plugin/plugin_api.h"

namespace rsvio {
namespace {

const char* kName = "solver.sparse";

// Through InnerIterator: an uncompressed matrix may hold unused slots in its value array.
bool allFinite(const Eigen::SparseMatrix<double>& H) {
  for (Eigen::Index j = 0; j < H.outerSize(); ++j)
    for (Eigen::SparseMatrix<double>::InnerIterator it(H, j); it; ++it)
      if (!std::isfinite(it.value())) return false;
  return true;
}

sparse::CholmodOptions optionsFrom(const Params& p) {
  sparse::CholmodOptions o;
  const std::string m = p.getString("method");
  o.method = m == "supernodal"   ? sparse::FactorMethod::Supernodal
             : m == "simplicial" ? sparse::FactorMethod::Simplicial
                                 : sparse::FactorMethod::Auto;
  const std::string ord = p.getString("ordering");
  o.ordering = ord == "metis"     ? sparse::Ordering::Metis
               : ord == "natural" ? sparse::Ordering::Natural
               : ord == "best"    ? sparse::Ordering::Best
                                  : sparse::Ordering::Amd;
  o.min_pivot_ratio = p.getDouble("min_pivot_ratio");
  o.supernodal_switch = p.getDouble("supernodal_switch");
  return o;
}

class SparseSolver : public SolverBackend {
 public:
  explicit SparseSolver(const Params& p)
      : full_system_(p.getBool("full_system")), options_(optionsFrom(p)), cache_(options_) {}

  bool prefersFullSystem() const override { return full_system_; }

  bool solveSparse(const Eigen::SparseMatrix<double>& H, const Eigen::VectorXd& b, Eigen::VectorXd& x,
                   SolverStats* stats) override {
    const auto t0 = std::chrono::steady_clock::now();
    std::string msg;
    bool ok = checkInput(H.rows(), H.cols(), b, msg);
    if (ok && !allFinite(H)) {
      msg = std::string(kName) + ": H or b holds NaN or inf";
      ok = false;
    }
    if (ok && H.rows() == 0) {
      x.resize(0);
    } else if (ok) {
      std::string why;
      ok = cache_.solve(H, b, x, why);
      std::ostringstream os;
      os << kName << ": ";
      if (!ok) {
        os << why;
      } else {
        os << (cache_.lastWasSupernodal() ? "supernodal LL'" : "simplicial LDL'") << ", n = " << H.rows()
           << ", nnz(L) = " << static_cast<long>(cache_.lastFactorNonZeros())
           << ", flops/nnz(L) = " << static_cast<long>(cache_.lastFlopsPerNonZero());
      }
      os << ", analyses " << cache_.analyses() << ", factorizations " << cache_.factorizations();
      msg = os.str();
    }
    finish(t0, msg, stats);
    return ok;
  }

  // The Schur-reduced camera system: dense LLT (see the file comment for why not CHOLMOD).
  bool solveDense(const Eigen::MatrixXd& H, const Eigen::VectorXd& b, Eigen::VectorXd& x,
                  SolverStats* stats) override {
    const auto t0 = std::chrono::steady_clock::now();
    std::string msg;
    bool ok = checkInput(H.rows(), H.cols(), b, msg);
    if (ok && !H.allFinite()) {
      msg = std::string(kName) + ": H or b holds NaN or inf";
      ok = false;
    }
    if (ok && H.rows() == 0) {
      x.resize(0);
    } else if (ok) {
      ok = denseLlt(H, b, x, msg);
    }
    finish(t0, msg, stats);
    return ok;
  }

 private:
  static bool checkInput(Eigen::Index rows, Eigen::Index cols, const Eigen::VectorXd& b, std::string& msg) {
    std::ostringstream os;
    os << kName << ": ";
    if (rows != cols || rows != b.size()) {
      os << "size mismatch: H is " << rows << "x" << cols << ", b has " << b.size() << " rows";
      msg = os.str();
      return false;
    }
    if (!b.allFinite()) {
      msg = os.str() + "H or b holds NaN or inf";
      return false;
    }
    return true;
  }

  bool denseLlt(const Eigen::MatrixXd& H, const Eigen::VectorXd& b, Eigen::VectorXd& x, std::string& msg) const {
    std::ostringstream os;
    os << kName << ": ";
    Eigen::LLT<Eigen::MatrixXd> llt(H);
    if (llt.info() != Eigen::Success) {
      msg = os.str() + "H is not positive definite (dense LLT failed)";
      return false;
    }
    const Eigen::VectorXd d = llt.matrixLLT().diagonal().array().square();
    Eigen::Index i_min = 0;
    const double dmin = d.minCoeff(&i_min);
    const double dmax = d.maxCoeff();
    if (!(dmin > options_.min_pivot_ratio * dmax)) {
      os << "H is not positive definite (pivot " << i_min << " = " << dmin << ", largest " << dmax
         << ", min_pivot_ratio " << options_.min_pivot_ratio << ")";
      msg = os.str();
      return false;
    }
    x = llt.solve(b);
    if (!x.allFinite()) {
      msg = os.str() + "the solution is not finite";
      return false;
    }
    return true;
  }

  static void finish(std::chrono::steady_clock::time_point t0, const std::string& msg, SolverStats* stats) {
    if (!stats) return;
    stats->ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    stats->message = msg;
  }

  bool full_system_;
  sparse::CholmodOptions options_;
  sparse::CholmodFactorCache cache_;
};

ParamTable sparseParams() {
  return {paramEnum("method", "auto", {"auto", "supernodal", "simplicial"},
                    "CHOLMOD factor kind: auto (supernodal when flops/nnz(L) >= supernodal_switch), supernodal LL', "
                    "simplicial LDL'"),
          paramDouble("supernodal_switch", 1000.0, 0.0, 1e9, "flops per nnz(L)",
                      "method auto picks supernodal at or above this; CHOLMOD's own 40 lost on every BA shape of "
                      "bench/solver_bench.cpp (flops/nnz(L) <= 64 there)"),
          paramEnum("ordering", "amd", {"amd", "metis", "natural", "best"},
                    "fill-reducing ordering: amd, metis, natural (none), best (CHOLMOD tries AMD then METIS)"),
          paramBool("full_system", true,
                    "ask the optimiser for the full sparse system (cameras and points, no Schur step); false: "
                    "Schur-reduced camera system solved by dense LLT"),
          paramDouble("min_pivot_ratio", 1e-14, 0.0, 1.0, "",
                      "H is refused as not positive definite when the smallest pivot <= this times the largest")};
}

void registerAll(PluginRegistrar& r) {
  r.add<SolverBackend>({kName, PluginKind::Solver, "1.0.0",
                        "Sparse Cholesky (SuiteSparse CHOLMOD) on the full system, analysis cached per pattern",
                        sparseParams(), ""},
                       [](const Params& p) { return std::make_unique<SparseSolver>(p); });
}

}  // namespace
}  // namespace rsvio

RSVIO_PLUGIN_ENTRY(rsvio::registerAll)
