// solver.sparse through the plugin host: agreement with solver.dense's Schur-reduced solve on systems
// of bundle-adjustment shape, refusal of indefinite systems, reuse of the symbolic analysis, messages.
// The generic solver contract runs on it from tests/plugins/solver/ (cases in its contract.json).
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <regex>

#include "ba_system.h"
#include "support/plugin_contracts.h"

namespace rsvio::test {
namespace {

struct Counters {
  long analyses = -1;
  long factorizations = -1;
};

// The counters solver.sparse reports in SolverStats::message.
Counters countersOf(const std::string& msg) {
  std::smatch m;
  Counters c;
  if (std::regex_search(msg, m, std::regex("analyses ([0-9]+), factorizations ([0-9]+)"))) {
    c.analyses = std::stol(m[1]);
    c.factorizations = std::stol(m[2]);
  }
  return c;
}

double relErr(const Eigen::VectorXd& a, const Eigen::VectorXd& ref) { return (a - ref).norm() / ref.norm(); }

class SparseVsSchur : public ::testing::TestWithParam<std::string> {};

// Full sparse CHOLMOD vs Schur complement + solver.dense + back-substitution: cameras and points to 1e-9.
TEST_P(SparseVsSchur, AgreesWithDenseSchurOnBaShapedSystems) {
  auto sparse = makePlugin<SolverBackend>("solver.sparse", {{"method", GetParam()}});
  auto dense = makePlugin<SolverBackend>("solver.dense");
  EXPECT_TRUE(sparse->prefersFullSystem());
  struct Shape {
    int k, n;
  };
  unsigned seed = 1;
  for (const Shape sh : {Shape{7, 300}, Shape{15, 500}, Shape{30, 400}}) {
    const BaSystem s = makeBaSystem(sh.k, sh.n, seed++);
    Eigen::VectorXd x;
    SolverStats st;
    ASSERT_TRUE(sparse->solveSparse(s.H, s.b, x, &st)) << st.message;
    ASSERT_EQ(x.size(), s.cams() + s.n);
    EXPECT_LT((s.H * x - s.b).norm() / s.b.norm(), 1e-10) << st.message;

    const SchurSystem r = schurReduce(s);
    Eigen::VectorXd xc;
    ASSERT_TRUE(dense->solveDense(r.S, r.bc, xc, &st)) << st.message;
    const Eigen::VectorXd xp = backSubstitute(r, xc);
    EXPECT_LT(relErr(x.head(s.cams()), xc), 1e-9) << "k = " << sh.k << ", n = " << sh.n;
    EXPECT_LT(relErr(x.tail(s.n), xp), 1e-9) << "k = " << sh.k << ", n = " << sh.n;

    // solveDense (Eigen LLT inside solver.sparse) on the reduced system agrees too.
    Eigen::VectorXd xc2;
    ASSERT_TRUE(sparse->solveDense(r.S, r.bc, xc2, &st)) << st.message;
    EXPECT_LT(relErr(xc2, xc), 1e-9);
  }
}

INSTANTIATE_TEST_SUITE_P(Methods, SparseVsSchur, ::testing::Values("auto", "supernodal", "simplicial"));

TEST(SparseSolver, OrderingsAgree) {
  const BaSystem s = makeBaSystem(10, 300, 21);
  Eigen::VectorXd x_ref;
  for (const char* ord : {"amd", "metis", "natural", "best"}) {
    auto solver = makePlugin<SolverBackend>("solver.sparse", {{"ordering", ord}});
    Eigen::VectorXd x;
    SolverStats st;
    ASSERT_TRUE(solver->solveSparse(s.H, s.b, x, &st)) << ord << ": " << st.message;
    if (x_ref.size() == 0) x_ref = x;
    EXPECT_LT(relErr(x, x_ref), 1e-10) << ord;
  }
}

// One camera-point coupling raised above sqrt(H_cc H_pp): that 2x2 principal minor is negative, so H is
// indefinite, while its pattern and its diagonal (all positive) are unchanged: only the factorisation can tell.
TEST(SparseSolver, IndefiniteBaSystemIsRefusedAndTheAnalysisSurvives) {
  const BaSystem s = makeBaSystem(7, 120, 5);
  Eigen::SparseMatrix<double> Hi = s.H;
  const int p = s.cams() + 40;
  const int c = static_cast<int>(Eigen::SparseMatrix<double>::InnerIterator(s.H, p).row());  // first coupling
  ASSERT_LT(c, s.cams());
  const double h = 2.0 * std::sqrt(s.H.coeff(c, c) * s.H.coeff(p, p));
  Hi.coeffRef(c, p) = Hi.coeffRef(p, c) = h;
  ASSERT_EQ(Hi.nonZeros(), s.H.nonZeros());
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es{Eigen::MatrixXd(Hi), Eigen::EigenvaluesOnly};
  ASSERT_LT(es.eigenvalues()[0], 0.0);
  Eigen::VectorXd x_dense;
  EXPECT_FALSE(makePlugin<SolverBackend>("solver.dense")->solveDense(Eigen::MatrixXd(Hi), s.b, x_dense));

  for (const char* method : {"auto", "supernodal", "simplicial"}) {
    auto solver = makePlugin<SolverBackend>("solver.sparse", {{"method", method}});
    Eigen::VectorXd x;
    SolverStats st;
    EXPECT_FALSE(solver->solveSparse(Hi, s.b, x, &st)) << method;
    EXPECT_NE(st.message.find("solver.sparse: H is not positive definite"), std::string::npos) << st.message;
    EXPECT_FALSE(solver->solveSparse(Hi, s.b, x, nullptr)) << method;
    // The same pattern, positive definite again (as after the optimiser raises the damping).
    ASSERT_TRUE(solver->solveSparse(s.H, s.b, x, &st)) << method << ": " << st.message;
    EXPECT_LT((s.H * x - s.b).norm() / s.b.norm(), 1e-10) << method;
    EXPECT_EQ(countersOf(st.message).analyses, 1) << st.message;
    EXPECT_EQ(countersOf(st.message).factorizations, 3) << st.message;
  }
}

TEST(SparseSolver, RepeatedSolvesWithOnePatternReuseTheAnalysis) {
  auto solver = makePlugin<SolverBackend>("solver.sparse");
  const BaSystem s = makeBaSystem(15, 400, 9);
  SolverStats st;
  Eigen::VectorXd x;
  for (int it = 0; it < 4; ++it) {
    // New values, same pattern: another Gauss-Newton iteration with different damping.
    Eigen::SparseMatrix<double> H = s.H;
    for (int i = 0; i < H.rows(); ++i) H.coeffRef(i, i) *= 1.0 + 0.5 * it;
    ASSERT_TRUE(solver->solveSparse(H, s.b, x, &st)) << st.message;
    EXPECT_LT((H * x - s.b).norm() / s.b.norm(), 1e-10);
    EXPECT_EQ(countersOf(st.message).analyses, 1) << st.message;
    EXPECT_EQ(countersOf(st.message).factorizations, it + 1) << st.message;
  }
  // A different pattern (another window) is analysed afresh, and the new analysis is reused in turn.
  const BaSystem s2 = makeBaSystem(15, 410, 10);
  for (int it = 0; it < 2; ++it) {
    ASSERT_TRUE(solver->solveSparse(s2.H, s2.b, x, &st)) << st.message;
    EXPECT_LT((s2.H * x - s2.b).norm() / s2.b.norm(), 1e-10);
    EXPECT_EQ(countersOf(st.message).analyses, 2) << st.message;
  }
  // Back to the first pattern: one more analysis (one pattern is cached, not a history).
  ASSERT_TRUE(solver->solveSparse(s.H, s.b, x, &st)) << st.message;
  EXPECT_EQ(countersOf(st.message).analyses, 3) << st.message;
  EXPECT_EQ(countersOf(st.message).factorizations, 7) << st.message;
}

// An uncompressed matrix with rows inserted out of order and a lower triangle that is not stored
// symmetric-exactly gives the same answer: only the upper triangle is read.
TEST(SparseSolver, ReadsTheUpperTriangleOfAnyStorage) {
  const BaSystem s = makeBaSystem(5, 60, 3);
  auto solver = makePlugin<SolverBackend>("solver.sparse");
  Eigen::VectorXd x_ref, x;
  ASSERT_TRUE(solver->solveSparse(s.H, s.b, x_ref));
  Eigen::SparseMatrix<double> U(s.H.rows(), s.H.cols());
  U.reserve(Eigen::VectorXi::Constant(s.H.cols(), 64));
  for (int j = static_cast<int>(s.H.cols()) - 1; j >= 0; --j)
    for (Eigen::SparseMatrix<double>::InnerIterator it(s.H, j); it; ++it)
      U.insert(it.row(), j) = it.row() > j ? 0.0 : it.value();  // lower triangle zeroed
  ASSERT_FALSE(U.isCompressed());
  auto fresh = makePlugin<SolverBackend>("solver.sparse");
  ASSERT_TRUE(fresh->solveSparse(U, s.b, x));
  EXPECT_LT(relErr(x, x_ref), 1e-12);
}

TEST(SparseSolver, MessagesSayWhy) {
  auto s = makePlugin<SolverBackend>("solver.sparse");
  Eigen::VectorXd x;
  SolverStats st;
  Eigen::SparseMatrix<double> I3(3, 3);
  I3.setIdentity();
  EXPECT_FALSE(s->solveSparse(I3, Eigen::Vector2d::Ones(), x, &st));
  EXPECT_EQ(st.message, "solver.sparse: size mismatch: H is 3x3, b has 2 rows");
  Eigen::SparseMatrix<double> Hn = I3;
  Hn.coeffRef(1, 1) = std::nan("");
  EXPECT_FALSE(s->solveSparse(Hn, Eigen::Vector3d::Ones(), x, &st));
  EXPECT_EQ(st.message, "solver.sparse: H or b holds NaN or inf");
  EXPECT_FALSE(s->solveDense(Eigen::Matrix3d::Identity(), Eigen::Vector3d(1.0, INFINITY, 0.0), x, &st));
  EXPECT_EQ(st.message, "solver.sparse: H or b holds NaN or inf");
  Eigen::Matrix2d H;
  H << 1.0, 2.0, 2.0, 1.0;
  EXPECT_FALSE(s->solveDense(H, Eigen::Vector2d::Ones(), x, &st));
  EXPECT_NE(st.message.find("solver.sparse: H is not positive definite"), std::string::npos) << st.message;
  EXPECT_TRUE(s->solveSparse(Eigen::SparseMatrix<double>(0, 0), Eigen::VectorXd(0), x, &st));
  EXPECT_EQ(x.size(), 0);
  EXPECT_TRUE(s->solveSparse(I3, Eigen::Vector3d(1.0, 2.0, 3.0), x, &st));
  EXPECT_LT((x - Eigen::Vector3d(1.0, 2.0, 3.0)).norm(), 1e-15);
  EXPECT_NE(st.message.find(", n = 3, nnz(L) = "), std::string::npos) << st.message;
}

TEST(SparseSolver, ParamsAreValidatedLikeAConfigSlot) {
  EXPECT_FALSE(makePlugin<SolverBackend>("solver.sparse", {{"full_system", false}})->prefersFullSystem());
  try {
    makePlugin<SolverBackend>("solver.sparse", {{"method", "qr"}});
    FAIL() << "method qr accepted";
  } catch (const ConfigError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("solver.sparse.params.method"), std::string::npos) << msg;
    EXPECT_NE(msg.find("supernodal"), std::string::npos) << msg;
  }
}

}  // namespace
}  // namespace rsvio::test
