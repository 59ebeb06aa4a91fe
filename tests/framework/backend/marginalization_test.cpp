// Marginalisation prior: equals the Schur complement of the full Hessian (keyframe and its points
// eliminated), keeps its linearisation point (first-estimate Jacobians), and its energy/gradient at
// moved states is the quadratic model around that point.
#include <gtest/gtest.h>

#include "ba_test_window.h"
#include "rsvio/backend/bundle_adjustment.h"
#include "rsvio/backend/marginalization.h"
#include "rsvio/interfaces/solver.h"
#include "support/numeric_jacobian.h"
#include "support/plugin_contracts.h"

namespace rsvio {
namespace {

using test::TestWindow;
using test::tw;

// Schur complement of the index set `elim` out of (H, b).
void schur(const Eigen::MatrixXd& H, const Eigen::VectorXd& b, const std::vector<int>& elim, Eigen::MatrixXd* Hr,
           Eigen::VectorXd* br) {
  std::vector<int> keep;
  for (int i = 0; i < H.rows(); ++i)
    if (std::find(elim.begin(), elim.end(), i) == elim.end()) keep.push_back(i);
  const int r = static_cast<int>(keep.size()), m = static_cast<int>(elim.size());
  Eigen::MatrixXd Hrr(r, r), Hrm(r, m), Hmm(m, m);
  Eigen::VectorXd bR(r), bM(m);
  for (int i = 0; i < r; ++i) {
    bR[i] = b[keep[i]];
    for (int j = 0; j < r; ++j) Hrr(i, j) = H(keep[i], keep[j]);
    for (int j = 0; j < m; ++j) Hrm(i, j) = H(keep[i], elim[j]);
  }
  for (int i = 0; i < m; ++i) {
    bM[i] = b[elim[i]];
    for (int j = 0; j < m; ++j) Hmm(i, j) = H(elim[i], elim[j]);
  }
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(Hmm);
  *Hr = Hrr - Hrm * ldlt.solve(Hrm.transpose());
  *br = bR - Hrm * ldlt.solve(bM);
}

TEST(Marginalization, PriorEqualsSchurComplementOfTheFullHessian) {
  TestWindow w(4);
  w.addPoints(0, 250);  // every point hosted by the keyframe that leaves: the elimination is exact
  auto solver = test::makePlugin<SolverBackend>("solver.dense");
  BundleAdjustmentConfig cfg;
  cfg.affine_prior_a = 50.0;  // keyframe priors go into the prior too
  cfg.affine_prior_b = 0.01;
  w.window[1]->state.affine = AffineBrightness{0.05, -2.0};
  BundleAdjuster ba(cfg, w.camera, w.timing, *solver);
  MarginalizationPrior empty;
  ba.linearize(w.window, empty);
  Eigen::MatrixXd H;
  Eigen::VectorXd b;
  ba.fullSystem(&H, &b);
  const int kd = cfg.layout.kfDim();
  const int nc = kd * 4;
  std::vector<int> elim;
  for (int i = 0; i < kd; ++i) elim.push_back(i);
  for (int i = nc; i < H.rows(); ++i) elim.push_back(i);
  Eigen::MatrixXd H_ref;
  Eigen::VectorXd b_ref;
  schur(H, b, elim, &H_ref, &b_ref);
  // The full system holds the keyframe priors of all keyframes; the prior receives keyframe 0's now
  // and the others' would stay in the window: remove theirs from the reference.
  for (int k = 1; k < 4; ++k) {
    Eigen::MatrixXd Hk;
    Eigen::VectorXd bk;
    ba.keyframePriorTerm(*w.window[static_cast<size_t>(k)], &Hk, &bk);
    H_ref.block((k - 1) * kd, (k - 1) * kd, kd, kd) -= Hk;
    b_ref.segment((k - 1) * kd, kd) -= bk;
  }

  MarginalizationPrior prior(cfg.layout);
  std::vector<int> blocks;
  Eigen::MatrixXd Ht;
  Eigen::VectorXd bt;
  ba.pointsTerm(w.window, ba.points(), 1.0, &blocks, &Ht, &bt);
  ASSERT_EQ(blocks, (std::vector<int>{0, 1, 2, 3}));
  std::vector<Keyframe*> kfs;
  for (int k : blocks) kfs.push_back(w.window[static_cast<size_t>(k)].get());
  prior.addTerm(kfs, Ht, bt);
  Eigen::MatrixXd H0;
  Eigen::VectorXd b0;
  ba.keyframePriorTerm(*w.window[0], &H0, &b0);
  prior.addTerm({w.window[0].get()}, H0, b0);
  prior.marginalizeKeyframe(w.window[0].get());
  ASSERT_EQ(prior.keyframes().size(), 3u);
  EXPECT_FALSE(w.window[0]->in_prior);
  const double scale = H_ref.cwiseAbs().maxCoeff();
  EXPECT_LT((prior.H() - H_ref).cwiseAbs().maxCoeff(), 1e-8 * scale);
  EXPECT_LT((prior.b() - b_ref).cwiseAbs().maxCoeff(), 1e-8 * (1.0 + b_ref.cwiseAbs().maxCoeff()));
}

TEST(Marginalization, LinearisationPointIsFrozenAndTheModelIsQuadraticAroundIt) {
  StateLayout layout;
  MarginalizationPrior prior(layout);
  Keyframe a, b;
  a.state.T_c_w = SE3d::exp(tw(0.1, 0.2, -0.1, 0.05, 0.02, -0.03));
  b.state.T_c_w = SE3d::exp(tw(-0.3, 0.1, 0.2, -0.02, 0.04, 0.01));
  a.index = 0;
  b.index = 1;
  const int d = layout.kfDim();
  // A random positive definite term over both keyframes, linearised at the current states.
  std::mt19937 rng(4);
  std::normal_distribution<double> n(0, 1);
  Eigen::MatrixXd J(3 * d, 2 * d);
  for (int i = 0; i < J.rows(); ++i)
    for (int j = 0; j < J.cols(); ++j) J(i, j) = n(rng);
  const Eigen::MatrixXd Ht = J.transpose() * J;
  Eigen::VectorXd bt(2 * d);
  for (int i = 0; i < bt.size(); ++i) bt[i] = n(rng);
  prior.addTerm({&a, &b}, Ht, bt);
  const KeyframeState lin_a = a.lin;
  EXPECT_TRUE(a.in_prior && b.in_prior);

  // Move the states, add the term again (relinearised at the new states): the prior's point stays.
  const Vec6 da = tw(0.01, -0.02, 0.005, 0.003, -0.004, 0.002);
  a.state.T_c_w = SE3d::exp(da) * a.state.T_c_w;
  a.state.affine.a = 0.02;
  b.state.affine.b = -1.5;
  prior.addTerm({&a, &b}, Ht, bt);
  EXPECT_EQ(a.lin.T_c_w.params(), lin_a.T_c_w.params());

  // At the moved states the contribution is H, b - H delta, and b - H delta = -(1/2) dE/dx for the
  // left perturbation up to the chart's first-order term (|delta| ~ 0.02 here).
  Eigen::MatrixXd Hw = Eigen::MatrixXd::Zero(2 * d, 2 * d);
  Eigen::VectorXd bw = Eigen::VectorXd::Zero(2 * d);
  prior.addTo(Hw, bw);
  EXPECT_LT((Hw - prior.H()).norm(), 1e-12 * Hw.norm());
  auto energyAt = [&](const Eigen::VectorXd& step) {
    Keyframe a2 = a, b2 = b;
    applyStep(a2.state, step.head(d), layout);
    applyStep(b2.state, step.tail(d), layout);
    Eigen::VectorXd dl(2 * d);
    dl.head(d) = stateDelta(a2.state, a.lin, layout);
    dl.tail(d) = stateDelta(b2.state, b.lin, layout);
    return dl.dot(prior.H() * dl) - 2.0 * prior.b().dot(dl);
  };
  const Eigen::MatrixXd g =
      test::numericJacobian(energyAt, Eigen::VectorXd::Zero(2 * d).eval(), test::VectorPlus(), 2 * d, 1e-6);
  EXPECT_LT((g.transpose() + 2.0 * bw).norm(), 3e-2 * (1.0 + bw.norm()));
  EXPECT_NEAR(prior.energy(), energyAt(Eigen::VectorXd::Zero(2 * d)), 1e-9 * (1.0 + std::abs(prior.energy())));
}

TEST(Marginalization, ScaleFreeTermKeepsTheScaleAtTheLinearisationPointsNull) {
  // A term linearised away from x_lin (here: at states scaled by 1.05 and rotated) is not
  // scale-invariant at x_lin; addScaleFreeTerm projects the scale direction at x_lin off it, so the
  // prior stays without information on the monocular scale; without the projection it has some (the
  // window also rotated by 0.05 rad, which turns the direction of the stacked translations).
  StateLayout layout;
  const int d = layout.kfDim();
  Keyframe a, b, c;
  a.state.T_c_w = SE3d::exp(tw(0.4, 0.2, -0.1, 0.05, 0.02, -0.03));
  b.state.T_c_w = SE3d::exp(tw(-0.3, 0.5, 0.2, -0.02, 0.04, 0.01));
  c.state.T_c_w = SE3d::exp(tw(0.1, -0.6, 0.7, 0.01, -0.05, 0.02));
  std::vector<Keyframe*> kfs{&a, &b, &c};
  for (int i = 0; i < 3; ++i) kfs[static_cast<size_t>(i)]->index = i;
  auto scaleDir = [&](bool lin) {
    Eigen::VectorXd n = Eigen::VectorXd::Zero(3 * d);
    for (int i = 0; i < 3; ++i) {
      const Keyframe& k = *kfs[static_cast<size_t>(i)];
      n.segment<3>(i * d + StateLayout::kPose) = (lin ? k.lin : k.state).T_c_w.translation();
    }
    return Eigen::VectorXd(n.normalized());
  };
  std::mt19937 rng(7);
  std::normal_distribution<double> nd(0, 1);
  auto randomTerm = [&](Eigen::MatrixXd* H, Eigen::VectorXd* g) {
    Eigen::MatrixXd J(4 * d, 3 * d);
    for (int i = 0; i < J.rows(); ++i)
      for (int j = 0; j < J.cols(); ++j) J(i, j) = nd(rng);
    const Eigen::VectorXd u = scaleDir(false);  // null at the CURRENT states, as a points term is
    J -= (J * u) * u.transpose();
    *H = J.transpose() * J;
    g->resize(3 * d);
    for (int i = 0; i < g->size(); ++i) (*g)[i] = nd(rng);
    *g -= u * u.dot(*g);
  };
  for (bool project : {false, true}) {
    MarginalizationPrior prior(layout);
    for (Keyframe* k : kfs) k->in_prior = false;
    a.state.T_c_w = SE3d::exp(tw(0.4, 0.2, -0.1, 0.05, 0.02, -0.03));
    b.state.T_c_w = SE3d::exp(tw(-0.3, 0.5, 0.2, -0.02, 0.04, 0.01));
    c.state.T_c_w = SE3d::exp(tw(0.1, -0.6, 0.7, 0.01, -0.05, 0.02));
    Eigen::MatrixXd H;
    Eigen::VectorXd g;
    randomTerm(&H, &g);
    prior.addScaleFreeTerm(kfs, H, g, project);
    for (Keyframe* k : kfs) k->state.T_c_w.translation() *= 1.05;  // the window's scale moved
    for (Keyframe* k : kfs) k->state.T_c_w = SE3d::exp(tw(0.0, 0.0, 0.0, 0.05, 0.0, 0.0)) * k->state.T_c_w;
    randomTerm(&H, &g);
    prior.addScaleFreeTerm(kfs, H, g, project);
    const Eigen::VectorXd u = scaleDir(true);
    const double info = u.dot(prior.H() * u) / prior.H().trace();
    if (project) {
      EXPECT_LT(info, 1e-12);
      EXPECT_LT(std::abs(u.dot(prior.b())), 1e-9 * prior.b().norm());
    } else {
      EXPECT_GT(info, 1e-6);
    }
  }
}

}  // namespace
}  // namespace rsvio
