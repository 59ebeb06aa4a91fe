// CHOLMOD Cholesky of a symmetric sparse matrix with its symbolic analysis cached.
//
// The bundle adjustment hands the solver the same sparsity pattern at every Gauss-Newton iteration
// of a window (only values and damping change), so the fill-reducing ordering and the symbolic
// factor (elimination tree, supernodes) are computed once per pattern and reused: a new analysis
// happens only when the upper-triangular pattern of H differs from the cached one.
//
// Contract
// - Only the upper triangle of H (row <= col) is read; H is assumed symmetric.
// - solve() returns false and a one-line reason when H is not positive definite (CHOLMOD reports a
//   non-positive pivot, or the smallest pivot <= min_pivot_ratio times the largest), when CHOLMOD
//   fails (out of memory), or when the solution is not finite.
// - One cholmod_common per object: two caches never share state, so two estimators can run side by
//   side. Not thread-safe (one object per thread).
// - SuiteSparse types stay inside this plugin; nothing CHOLMOD-specific crosses the plugin boundary.
#pragma once
#include <cholmod.h>

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <sstream>
#include <string>
#include <vector>

namespace rsvio::sparse {

enum class FactorMethod { Auto, Supernodal, Simplicial };
enum class Ordering { Amd, Metis, Natural, Best };

struct CholmodOptions {
  FactorMethod method = FactorMethod::Auto;
  Ordering ordering = Ordering::Amd;
  double min_pivot_ratio = 1e-14;
  double supernodal_switch = 1000.0;  // Auto: supernodal when flops / nnz(L) >= this (CHOLMOD's own is 40)
};

class CholmodFactorCache {
 public:
  explicit CholmodFactorCache(const CholmodOptions& options);
  ~CholmodFactorCache();
  CholmodFactorCache(const CholmodFactorCache&) = delete;
  CholmodFactorCache& operator=(const CholmodFactorCache&) = delete;

  // Solves H x = b (square, sizes checked and values finite by the caller). On failure `why` says why.
  bool solve(const Eigen::SparseMatrix<double>& H, const Eigen::VectorXd& b, Eigen::VectorXd& x, std::string& why);

  long analyses() const { return analyses_; }              // symbolic analyses done (new patterns)
  long factorizations() const { return factorizations_; }  // numeric factorizations done
  bool lastWasSupernodal() const { return last_supernodal_; }
  double lastFactorNonZeros() const { return last_nnz_l_; }  // entries of L (CHOLMOD's lnz)
  double lastFlopsPerNonZero() const { return last_fl_per_lnz_; }  // CHOLMOD's fl / lnz, what Auto decides on

 private:
  // Copies the upper triangle of H into the scratch arrays; true when its pattern equals the cached A_'s.
  bool loadUpper(const Eigen::SparseMatrix<double>& H);
  void release();
  // Every pivot of the fresh factor > min_pivot_ratio times the largest; else a reason into os.
  bool pivotsOk(std::ostringstream& os);

  CholmodOptions options_;
  cholmod_common c_;
  cholmod_sparse* A_ = nullptr;  // upper triangle, stype = 1; pattern cached, values refreshed per call
  cholmod_factor* L_ = nullptr;  // symbolic analysis of A_'s pattern, refactorised per call
  std::vector<int> p_, i_;       // scratch: column pointers and row indices of the incoming upper triangle
  std::vector<double> x_;
  bool sorted_ = true;
  long analyses_ = 0;
  long factorizations_ = 0;
  bool last_supernodal_ = false;
  double last_nnz_l_ = 0.0;
  double last_fl_per_lnz_ = 0.0;
};

}  // namespace rsvio::sparse
