// Solver backends on bundle-adjustment-shaped systems (issue 8): where does the sparse full-system
// CHOLMOD solve (solver.sparse) beat the Schur complement + dense Cholesky (solver.dense)?
//
// Systems: k keyframes x 8 parameters and n points x 1, each point seen by 2-5 keyframes near its
// host, 2 residual rows per observation (tests/plugins/solver/sparse/ba_system.h).
//   DenseSchur       builds S = Hcc - Hcp Hpp^-1 Hpc from the per-point 8x1 blocks (as the BA keeps
//                    them), solves with solver.dense (LDLT), back-substitutes the points.
//   SparseFull       solver.sparse on the full system, analysis cached (the steady state: every
//                    iteration of one window has the same pattern).
//   SparseFullFresh  the same with a new analysis per call (the first iteration of a new window).
//   SparseSimplicial / SparseSupernodal  the cached solve with the factor kind forced (what auto chooses from).
// Compare CPU times: the label shows the factor kind, nnz(L) and flops/nnz(L) of the sparse solves.
// Plugins load through the host like the app's: $RSVIO_PLUGIN_PATH, else <bin>/plugins.
// Run: <build>/bin/solver_bench [--benchmark_filter=...]
#include <benchmark/benchmark.h>

#include <map>
#include <memory>
#include <stdexcept>
#include <utility>
#include <vector>

#include "plugins/solver/sparse/ba_system.h"
#include "rsvio/config/validate.h"
#include "rsvio/interfaces/solver.h"
#include "rsvio/plugin/host.h"

namespace rsvio {
namespace {

PluginHost& host() {
  static PluginHost h(PluginHost::defaultSearchPath({}));
  return h;
}

// Default params resolved from the plugin's own table, as a config slot would be.
std::unique_ptr<SolverBackend> makeSolver(const std::string& name,
                                          const nlohmann::json& params = nlohmann::json::object()) {
  std::vector<ConfigProblem> problems;
  const nlohmann::json p = validateParams(params, host().info(name).params, name, problems);
  if (!problems.empty()) throw std::runtime_error(problems.front().str());
  return host().create<SolverBackend>(name, Params(p, name));
}

// The full system plus the per-point blocks the dense Schur path works from.
struct Problem {
  test::BaSystem sys;
  Eigen::MatrixXd Hcc;
  std::vector<std::vector<std::pair<int, double>>> hcp;  // per point: (camera row, value)
  Eigen::VectorXd hpp;
};

const Problem& problem(int k, int n) {
  static std::map<std::pair<int, int>, Problem> cache;  // bench-local; built once per shape
  auto it = cache.find({k, n});
  if (it != cache.end()) return it->second;
  Problem p;
  p.sys = test::makeBaSystem(k, n, 1000u + 17u * static_cast<unsigned>(k) + static_cast<unsigned>(n));
  const int nc = p.sys.cams();
  p.Hcc = Eigen::MatrixXd(p.sys.H.topLeftCorner(nc, nc));
  p.hcp.resize(static_cast<size_t>(n));
  p.hpp.resize(n);
  for (int j = 0; j < n; ++j)
    for (Eigen::SparseMatrix<double>::InnerIterator e(p.sys.H, nc + j); e; ++e) {
      if (e.row() < nc) p.hcp[static_cast<size_t>(j)].emplace_back(static_cast<int>(e.row()), e.value());
      if (e.row() == nc + j) p.hpp[j] = e.value();
    }
  return cache.emplace(std::make_pair(k, n), std::move(p)).first->second;
}

void setCounters(benchmark::State& st, const Problem& p) {
  st.counters["unknowns"] = static_cast<double>(p.sys.H.rows());
  st.counters["nnz_H"] = static_cast<double>(p.sys.H.nonZeros());
}

void BM_DenseSchur(benchmark::State& st) {
  const Problem& p = problem(static_cast<int>(st.range(0)), static_cast<int>(st.range(1)));
  auto solver = makeSolver("solver.dense");
  const int nc = p.sys.cams();
  const Eigen::VectorXd bp = p.sys.b.tail(p.sys.n);
  Eigen::MatrixXd S;
  Eigen::VectorXd bc, xc, xp(p.sys.n);
  for (auto _ : st) {
    S = p.Hcc;
    bc = p.sys.b.head(nc);
    for (int j = 0; j < p.sys.n; ++j) {
      const auto& col = p.hcp[static_cast<size_t>(j)];
      const double inv = 1.0 / p.hpp[j];
      for (const auto& [ra, va] : col) {
        const double wa = va * inv;
        bc[ra] -= wa * bp[j];
        for (const auto& [rb, vb] : col) S(ra, rb) -= wa * vb;
      }
    }
    if (!solver->solveDense(S, bc, xc)) st.SkipWithError("dense solve failed");
    for (int j = 0; j < p.sys.n; ++j) {
      double r = bp[j];
      for (const auto& [ra, va] : p.hcp[static_cast<size_t>(j)]) r -= va * xc[ra];
      xp[j] = r / p.hpp[j];
    }
    benchmark::DoNotOptimize(xp.data());
  }
  setCounters(st, p);
}

void sparseBench(benchmark::State& st, bool fresh, const nlohmann::json& params = nlohmann::json::object()) {
  const Problem& p = problem(static_cast<int>(st.range(0)), static_cast<int>(st.range(1)));
  auto solver = makeSolver("solver.sparse", params);
  Eigen::VectorXd x;
  SolverStats stats;
  if (!fresh && !solver->solveSparse(p.sys.H, p.sys.b, x, &stats)) st.SkipWithError(stats.message.c_str());
  for (auto _ : st) {
    if (fresh) {
      st.PauseTiming();
      solver = makeSolver("solver.sparse", params);
      st.ResumeTiming();
    }
    if (!solver->solveSparse(p.sys.H, p.sys.b, x, &stats)) st.SkipWithError(stats.message.c_str());
    benchmark::DoNotOptimize(x.data());
  }
  setCounters(st, p);
  st.SetLabel(stats.message.substr(stats.message.find(' ') + 1));
}

void BM_SparseFull(benchmark::State& st) { sparseBench(st, false); }
void BM_SparseFullFresh(benchmark::State& st) { sparseBench(st, true); }
void BM_SparseSimplicial(benchmark::State& st) { sparseBench(st, false, {{"method", "simplicial"}}); }
void BM_SparseSupernodal(benchmark::State& st) { sparseBench(st, false, {{"method", "supernodal"}}); }

void shapes(benchmark::internal::Benchmark* b) {
  b->ArgNames({"kf", "points"});
  for (int k : {7, 15, 30, 60})
    for (int n : {800, 2000, 8000}) b->Args({k, n});
  b->Unit(benchmark::kMillisecond);
}

BENCHMARK(BM_DenseSchur)->Apply(shapes);
BENCHMARK(BM_SparseFull)->Apply(shapes);
BENCHMARK(BM_SparseFullFresh)->Apply(shapes);
BENCHMARK(BM_SparseSimplicial)->Apply(shapes);
BENCHMARK(BM_SparseSupernodal)->Apply(shapes);

}  // namespace
}  // namespace rsvio

BENCHMARK_MAIN();
