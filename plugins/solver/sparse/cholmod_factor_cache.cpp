// CHOLMOD factorisation with the symbolic analysis cached per sparsity pattern (see the header).
#include "cholmod_factor_cache.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstring>
#include <sstream>

namespace rsvio::sparse {

CholmodFactorCache::CholmodFactorCache(const CholmodOptions& options) : options_(options) {
  cholmod_start(&c_);
  // Errors come back as return values and a message of ours; CHOLMOD itself stays silent.
  c_.print = 0;
  c_.error_handler = nullptr;
  switch (options_.method) {
    case FactorMethod::Auto:
      c_.supernodal = CHOLMOD_AUTO;
      c_.supernodal_switch = options_.supernodal_switch;
      break;
    case FactorMethod::Supernodal: c_.supernodal = CHOLMOD_SUPERNODAL; break;
    case FactorMethod::Simplicial: c_.supernodal = CHOLMOD_SIMPLICIAL; break;
  }
  // Simplicial factors stay LDL' (CHOLMOD's default, no square roots); supernodal ones are always LL'.
  switch (options_.ordering) {
    case Ordering::Amd:
      c_.nmethods = 1;
      c_.method[0].ordering = CHOLMOD_AMD;
      break;
    case Ordering::Metis:
      c_.nmethods = 1;
      c_.method[0].ordering = CHOLMOD_METIS;
      break;
    case Ordering::Natural:
      c_.nmethods = 1;
      c_.method[0].ordering = CHOLMOD_NATURAL;
      break;
    case Ordering::Best:
      c_.nmethods = 0;  // CHOLMOD's default strategy: AMD, then METIS if AMD's fill is high
      break;
  }
}

CholmodFactorCache::~CholmodFactorCache() {
  release();
  cholmod_finish(&c_);
}

void CholmodFactorCache::release() {
  if (L_) cholmod_free_factor(&L_, &c_);
  if (A_) cholmod_free_sparse(&A_, &c_);
}

bool CholmodFactorCache::loadUpper(const Eigen::SparseMatrix<double>& H) {
  const int n = static_cast<int>(H.cols());
  p_.assign(static_cast<size_t>(n) + 1, 0);
  i_.clear();
  x_.clear();
  i_.reserve(static_cast<size_t>(H.nonZeros()));
  x_.reserve(static_cast<size_t>(H.nonZeros()));
  sorted_ = true;
  for (int j = 0; j < n; ++j) {
    int last = -1;
    for (Eigen::SparseMatrix<double>::InnerIterator it(H, j); it; ++it) {
      const int r = static_cast<int>(it.row());
      if (r > j) continue;
      if (r <= last) sorted_ = false;
      last = r;
      i_.push_back(r);
      x_.push_back(it.value());
    }
    p_[static_cast<size_t>(j) + 1] = static_cast<int>(i_.size());
  }
  if (!A_ || static_cast<int>(A_->nrow) != n || static_cast<int*>(A_->p)[n] != p_.back()) return false;
  return std::memcmp(A_->p, p_.data(), p_.size() * sizeof(int)) == 0 &&
         std::memcmp(A_->i, i_.data(), i_.size() * sizeof(int)) == 0;
}

bool CholmodFactorCache::pivotsOk(std::ostringstream& os) {
  if (!L_->is_super && !L_->is_ll) {
    // Simplicial LDL' does not pivot and CHOLMOD accepts negative entries of D (it factors some
    // indefinite matrices), so the sign test is ours: D(j) is the first entry of column j.
    const int* Lp = static_cast<const int*>(L_->p);
    const double* Lx = static_cast<const double*>(L_->x);
    double dmin = INFINITY, dmax = 0.0;
    size_t j_min = 0;
    for (size_t j = 0; j < L_->n; ++j) {
      const double d = Lx[Lp[j]];
      if (!(d >= dmin)) {
        dmin = d;
        j_min = j;
      }
      dmax = std::max(dmax, std::abs(d));
    }
    if (!(dmax > 0.0) || !(dmin > options_.min_pivot_ratio * dmax)) {
      os << "H is not positive definite (LDL' pivot " << j_min << " of " << L_->n
         << " in the fill-reducing order = " << dmin << ", largest " << dmax << ", min_pivot_ratio "
         << options_.min_pivot_ratio << ")";
      return false;
    }
    return true;
  }
  // LL' (CHOLMOD stops at a non-positive pivot): rcond = (min/max diag(L))^2, the pivot ratio of solver.dense.
  const double rcond = cholmod_rcond(L_, &c_);
  if (!(rcond > options_.min_pivot_ratio)) {
    os << "H is not positive definite (smallest pivot / largest = " << rcond << " <= min_pivot_ratio "
       << options_.min_pivot_ratio << ")";
    return false;
  }
  return true;
}

bool CholmodFactorCache::solve(const Eigen::SparseMatrix<double>& H, const Eigen::VectorXd& b, Eigen::VectorXd& x,
                               std::string& why) {
  std::ostringstream os;
  if (H.nonZeros() >= INT_MAX || H.rows() >= INT_MAX) {
    os << "H has " << H.nonZeros() << " non-zeros, beyond CHOLMOD's int interface";
    why = os.str();
    return false;
  }
  const int n = static_cast<int>(H.rows());
  if (!loadUpper(H)) {
    // New pattern: a fresh fill-reducing ordering and symbolic factor.
    release();
    A_ = cholmod_allocate_sparse(static_cast<size_t>(n), static_cast<size_t>(n), std::max<size_t>(i_.size(), 1),
                                 sorted_ ? 1 : 0, 1, 1, CHOLMOD_REAL, &c_);
    if (!A_) {
      why = "CHOLMOD could not allocate H (status " + std::to_string(c_.status) + ")";
      return false;
    }
    std::memcpy(A_->p, p_.data(), p_.size() * sizeof(int));
    std::memcpy(A_->i, i_.data(), i_.size() * sizeof(int));
    L_ = cholmod_analyze(A_, &c_);
    if (!L_ || c_.status < CHOLMOD_OK) {
      why = "CHOLMOD's symbolic analysis failed (status " + std::to_string(c_.status) + ")";
      release();
      return false;
    }
    ++analyses_;
    last_fl_per_lnz_ = c_.lnz > 0.0 ? c_.fl / c_.lnz : 0.0;
  }
  std::memcpy(A_->x, x_.data(), x_.size() * sizeof(double));

  // A failed factorisation leaves L_ as a valid (partial) factor of the same pattern, so the cached
  // analysis survives a refused system: the optimiser raises the damping and calls again.
  cholmod_factorize(A_, L_, &c_);
  ++factorizations_;
  last_supernodal_ = L_->is_super != 0;
  last_nnz_l_ = c_.lnz;
  if (c_.status == CHOLMOD_NOT_POSDEF || L_->minor < L_->n) {
    os << "H is not positive definite (CHOLMOD: non-positive pivot at step " << L_->minor << " of " << n
       << " in the fill-reducing order)";
    why = os.str();
    return false;
  }
  if (c_.status < CHOLMOD_OK) {
    why = "CHOLMOD's factorisation failed (status " + std::to_string(c_.status) + ")";
    return false;
  }
  if (!pivotsOk(os)) {
    why = os.str();
    return false;
  }

  // B wraps b without a copy; cholmod_solve only reads it.
  cholmod_dense B;
  std::memset(&B, 0, sizeof(B));
  B.nrow = B.d = B.nzmax = static_cast<size_t>(n);
  B.ncol = 1;
  B.x = const_cast<double*>(b.data());
  B.xtype = CHOLMOD_REAL;
  B.dtype = CHOLMOD_DOUBLE;
  cholmod_dense* X = cholmod_solve(CHOLMOD_A, L_, &B, &c_);
  if (!X) {
    why = "CHOLMOD's solve failed (status " + std::to_string(c_.status) + ")";
    return false;
  }
  x = Eigen::Map<const Eigen::VectorXd>(static_cast<const double*>(X->x), n);
  cholmod_free_dense(&X, &c_);
  if (!x.allFinite()) {
    why = "the solution is not finite";
    return false;
  }
  return true;
}

}  // namespace rsvio::sparse
