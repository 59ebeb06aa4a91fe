// Interface of solver.* plugins: linear solvers for the Gauss-Newton normal equations H dx = b.
//
// Contract
// - H is symmetric positive semi-definite (damping already added by the caller), b the right-hand side.
//   On success x holds the solution and true is returned; when H is not positive definite the solver
//   returns false and fills stats->message instead of producing garbage.
// - solveDense() for the Schur-reduced camera system (small, dense). solveSparse() for a full sparse
//   system (no Schur step: cameras and points together); the default densifies.
// - prefersFullSystem(): the optimiser hands this backend the full sparse system instead of the
//   Schur complement.
#pragma once
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <string>

#include "rsvio/plugin/plugin.h"

namespace rsvio {

struct SolverStats {
  double ms = 0.0;
  std::string message;
};

class SolverBackend : public PluginBase {
 public:
  static constexpr PluginKind kKind = PluginKind::Solver;

  virtual bool solveDense(const Eigen::MatrixXd& H, const Eigen::VectorXd& b, Eigen::VectorXd& x,
                          SolverStats* stats = nullptr) = 0;
  virtual bool solveSparse(const Eigen::SparseMatrix<double>& H, const Eigen::VectorXd& b, Eigen::VectorXd& x,
                           SolverStats* stats = nullptr) {
    return solveDense(Eigen::MatrixXd(H), b, x, stats);
  }
  virtual bool prefersFullSystem() const { return false; }
};

}  // namespace rsvio
