// Dynamic marginalisation (backend/dynamic_marginalization.h): which prior holds which terms, when the
// priors switch, and that the three share their linearisation points. The terms are random positive
// definite matrices over two keyframes in the inertial layout (with the global block): what matters
// here is where each term ends up, not its shape.
#include <gtest/gtest.h>

#include <random>

#include "rsvio/backend/dynamic_marginalization.h"

namespace rsvio {
namespace {

StateLayout inertialLayout() {
  StateLayout l;
  l.inertial = true;
  return l;
}

struct Term {
  Eigen::MatrixXd H;
  Eigen::VectorXd b;
};

Term randomTerm(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> nd(0, 1);
  Eigen::MatrixXd J(n + 3, n);
  for (int i = 0; i < J.rows(); ++i)
    for (int j = 0; j < J.cols(); ++j) J(i, j) = nd(rng);
  Term t{J.transpose() * J, Eigen::VectorXd(n)};
  for (int i = 0; i < n; ++i) t.b[i] = nd(rng);
  return t;
}

// Two keyframes and the global states; terms over both keyframes (stateDim rows each) and the global
// block. The states never move, so the priors' H and b are plain sums of the terms.
struct Fixture {
  StateLayout layout = inertialLayout();
  Keyframe a, b;
  GlobalStates globals;
  int n = 2 * layout.stateDim() + layout.globalDim();
  Term visual = randomTerm(n, 1), s0 = randomTerm(n, 2), s1 = randomTerm(n, 3), s2 = randomTerm(n, 4);

  DynamicMarginalization make(bool enabled, double interval = 1.1) {
    a.index = 0;
    b.index = 1;
    DynamicMarginalization dm(layout, DynamicMarginalizationOptions{enabled, interval});
    dm.setGlobals(&globals);
    return dm;
  }
  void addVisual(DynamicMarginalization& dm) { dm.addTerm({&a, &b}, visual.H, visual.b, true); }
  void addScale(DynamicMarginalization& dm, const Term& t) { dm.addScaleTerm({&a, &b}, t.H, t.b, true); }
};

// The prior's H as a sum of the given terms (the same block order: a, b, global).
void expectHolds(const MarginalizationPrior& p, std::initializer_list<const Term*> terms, const char* what) {
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(p.H().rows(), p.H().cols());
  Eigen::VectorXd b = Eigen::VectorXd::Zero(p.b().size());
  for (const Term* t : terms) {
    H += t->H;
    b += t->b;
  }
  ASSERT_EQ(H.rows(), p.H().rows()) << what;
  EXPECT_LT((p.H() - H).norm(), 1e-9 * (1.0 + H.norm())) << what;
  EXPECT_LT((p.b() - b).norm(), 1e-9 * (1.0 + b.norm())) << what;
}

TEST(DynamicMarginalization, DisabledIsOnePriorWithEveryTerm) {
  Fixture f;
  DynamicMarginalization dm = f.make(false);
  f.addVisual(dm);
  f.addScale(dm, f.s0);
  dm.start(1.0, 0.0);
  EXPECT_FALSE(dm.started());
  EXPECT_EQ(dm.update(2.0, 1.0), DynamicMarginalization::Event::kNone);
  expectHolds(dm.active(), {&f.visual, &f.s0}, "current");
  EXPECT_TRUE(dm.visual().empty());
  EXPECT_TRUE(dm.half().empty());
}

TEST(DynamicMarginalization, ScaleTermsStayOutOfTheVisualPrior) {
  Fixture f;
  DynamicMarginalization dm = f.make(true);
  f.addVisual(dm);
  dm.start(1.0, 0.0);
  f.addScale(dm, f.s0);
  expectHolds(dm.visual(), {&f.visual}, "visual");
  expectHolds(dm.active(), {&f.visual, &f.s0}, "current");
  expectHolds(dm.half(), {&f.visual, &f.s0}, "half");
  EXPECT_EQ(dm.update(1.05, 1.0), DynamicMarginalization::Event::kNone);  // same half, inside
  expectHolds(dm.active(), {&f.visual, &f.s0}, "current after a small move");
}

TEST(DynamicMarginalization, CrossingTheCentreRestartsTheHalfOnly) {
  Fixture f;
  DynamicMarginalization dm = f.make(true);
  f.addVisual(dm);
  dm.start(1.0, 0.0);
  f.addScale(dm, f.s0);  // upper half (s = 1.0 >= s_mid)
  EXPECT_EQ(dm.update(0.97, 1.0), DynamicMarginalization::Event::kHalfReset);
  f.addScale(dm, f.s1);  // lower half
  expectHolds(dm.active(), {&f.visual, &f.s0, &f.s1}, "current");
  expectHolds(dm.half(), {&f.visual, &f.s1}, "half");
  EXPECT_EQ(dm.numHalfResets(), 1);
  EXPECT_EQ(dm.numSwitches(), 0);
  EXPECT_DOUBLE_EQ(dm.centre(), 1.0);
}

TEST(DynamicMarginalization, LeavingTheIntervalSwitchesToTheHalfAndMovesTheCentreToTheBound) {
  Fixture f;
  DynamicMarginalization dm = f.make(true, 1.1);
  f.addVisual(dm);
  dm.start(1.0, 0.0);
  f.addScale(dm, f.s0);                                  // upper half
  ASSERT_EQ(dm.update(0.95, 1.0), DynamicMarginalization::Event::kHalfReset);
  f.addScale(dm, f.s1);                                  // lower half
  EXPECT_EQ(dm.update(0.89, 2.0), DynamicMarginalization::Event::kSwitch);  // below 1 / 1.1
  // The terms linearised in the upper half (s0) are gone from the current prior.
  expectHolds(dm.active(), {&f.visual, &f.s1}, "current after the switch");
  expectHolds(dm.half(), {&f.visual}, "half after the switch");
  EXPECT_NEAR(dm.centre(), 1.0 / 1.1, 1e-12);
  // s = 0.89 is below the new centre: the lower half; new terms go to current and half.
  f.addScale(dm, f.s2);
  expectHolds(dm.active(), {&f.visual, &f.s1, &f.s2}, "current");
  expectHolds(dm.half(), {&f.visual, &f.s2}, "half");
  ASSERT_EQ(dm.events().size(), 3u);
  EXPECT_EQ(dm.events()[0].event, DynamicMarginalization::Event::kStart);
  EXPECT_EQ(dm.events()[2].event, DynamicMarginalization::Event::kSwitch);
  EXPECT_DOUBLE_EQ(dm.events()[2].t_s, 2.0);
}

TEST(DynamicMarginalization, AJumpOverTwoIntervalsLeavesOnlyTheVisualTerms) {
  Fixture f;
  DynamicMarginalization dm = f.make(true, 1.1);
  f.addVisual(dm);
  dm.start(1.0, 0.0);
  f.addScale(dm, f.s0);
  EXPECT_EQ(dm.update(1.35, 1.0), DynamicMarginalization::Event::kSwitch);  // > 1.1^3
  expectHolds(dm.active(), {&f.visual}, "current");
  EXPECT_EQ(dm.numSwitches(), 3);
  EXPECT_NEAR(dm.centre(), 1.1 * 1.1 * 1.1, 1e-12);
  EXPECT_LE(dm.centre() / 1.1, 1.35);
  EXPECT_GE(dm.centre() * 1.1, 1.35);
}

// The three priors share one linearisation point per keyframe: a keyframe that got its block in
// current and half through a scale term keeps that point when the visual prior gives it a block later
// at moved states (a second freeze would shift the other priors' quadratics).
TEST(DynamicMarginalization, PriorsShareTheLinearisationPoints) {
  Fixture f;
  DynamicMarginalization dm = f.make(true);
  dm.start(1.0, 0.0);
  f.addScale(dm, f.s0);
  EXPECT_TRUE(f.a.in_prior);
  const KeyframeState lin = f.a.lin;
  f.a.state.T_c_w = SE3d::exp((Vec6() << 0.1, 0.0, 0.0, 0.0, 0.02, 0.0).finished()) * f.a.state.T_c_w;
  f.addVisual(dm);
  EXPECT_EQ(f.a.lin.T_c_w.params(), lin.T_c_w.params());
  EXPECT_EQ(dm.visual().blockOf(&f.a), 0);
  // The visual term entered every prior at the same delta: the same b shift in each.
  const Eigen::VectorXd dv = dm.visual().b() - f.visual.b;
  const Eigen::VectorXd dc = dm.active().b() - f.visual.b - f.s0.b;
  EXPECT_GT(dv.norm(), 1e-6);
  EXPECT_LT((dv - dc).norm(), 1e-9 * (1.0 + dv.norm()));
}

TEST(DynamicMarginalization, MarginalisingAKeyframeRemovesItFromEveryPrior) {
  Fixture f;
  DynamicMarginalization dm = f.make(true);
  f.addVisual(dm);
  dm.start(1.0, 0.0);
  f.addScale(dm, f.s0);
  dm.marginalizeKeyframe(&f.a);
  const DynamicMarginalization& c = dm;
  for (const MarginalizationPrior* p : {&c.visual(), &c.active(), &c.half()}) {
    EXPECT_EQ(p->blockOf(&f.a), -1);
    EXPECT_EQ(p->H().rows(), f.layout.stateDim() + f.layout.globalDim());
  }
}

}  // namespace
}  // namespace rsvio
