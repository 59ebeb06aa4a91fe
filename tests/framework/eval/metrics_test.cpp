// ATE and RPE on synthetic trajectories whose answer is known in closed form.
#include "rsvio/eval/trajectory_metrics.h"

#include <gtest/gtest.h>

#include "eval_test_util.h"
#include "rsvio/core/error.h"

using namespace rsvio;
using namespace rsvio::eval;

namespace {

constexpr int64_t kStepNs = 125'000'000;  // 8 Hz: 0.125 s and 0.125 m steps are exact in binary

// Ground truth along x at 1 m/s with identity orientation; the estimate at `speed` m/s turning about
// z at `yaw_deg_per_s`. Positions and stamps are exact binary fractions, so steps land exactly.
void straightLine(double speed, double yaw_deg_per_s, io::Trajectory& gt, io::Trajectory& est, int n = 161) {
  gt = io::Trajectory{};
  est = io::Trajectory{};
  for (int i = 0; i < n; ++i) {
    io::StampedPose g;
    g.t_ns = i * kStepNs;
    g.p_W_X = Eigen::Vector3d(0.125 * i, 0, 0);
    gt.poses.push_back(g);
    io::StampedPose e = g;
    e.p_W_X.x() = speed * 0.125 * i;
    e.q_W_X = Eigen::AngleAxisd(yaw_deg_per_s * 0.125 * i * M_PI / 180.0, Eigen::Vector3d::UnitZ());
    est.poses.push_back(e);
  }
}

const RpeResult& findStep(const EvalResult& r, RpeStep::Kind kind, double value) {
  for (const auto& e : r.rpe) {
    if (e.step.kind == kind && std::abs(e.step.value - value) < 1e-12) return e;
  }
  throw std::runtime_error("no such RPE step");
}

}  // namespace

TEST(Stats, RmseMeanMedianMax) {
  const ErrorStats s = computeStats({3.0, 4.0, 1.0, 2.0});
  EXPECT_EQ(s.n, 4u);
  EXPECT_DOUBLE_EQ(s.mean, 2.5);
  EXPECT_DOUBLE_EQ(s.median, 2.5);
  EXPECT_DOUBLE_EQ(s.max, 4.0);
  EXPECT_DOUBLE_EQ(s.min, 1.0);
  EXPECT_DOUBLE_EQ(s.rmse, std::sqrt(30.0 / 4.0));
  EXPECT_DOUBLE_EQ(computeStats({5.0, 1.0, 3.0}).median, 3.0);
  EXPECT_EQ(computeStats({}).n, 0u);
}

TEST(Rpe, ScaleDriftGivesKnownTranslationError) {
  io::Trajectory gt, est;
  straightLine(1.25, 0.0, gt, est);
  EvalOptions opt;
  opt.align = AlignMode::kNone;
  opt.rpe_path_fractions = {0.1};  // 10 % of 20 m = 2 m
  opt.rpe_distances_m = {1.0};
  opt.rpe_windows_s = {1.0};
  const EvalResult r = evaluateTrajectory(gt, est, opt);
  EXPECT_DOUBLE_EQ(r.gt_path_length_m, 20.0);

  const RpeResult& d2 = findStep(r, RpeStep::Kind::kDistance, 2.0);
  EXPECT_EQ(d2.pairs, 161u - 16u);
  EXPECT_NEAR(d2.trans_m.rmse, 0.5, 1e-12);  // 25 % of 2 m, every pair
  EXPECT_NEAR(d2.trans_m.max, 0.5, 1e-12);
  EXPECT_NEAR(d2.drift_percent_mean, 25.0, 1e-9);
  EXPECT_NEAR(d2.rot_deg.max, 0.0, 1e-12);
  EXPECT_DOUBLE_EQ(d2.step.path_fraction, 0.1);

  const RpeResult& d1 = findStep(r, RpeStep::Kind::kDistance, 1.0);
  EXPECT_NEAR(d1.trans_m.mean, 0.25, 1e-12);

  const RpeResult& w1 = findStep(r, RpeStep::Kind::kTime, 1.0);
  EXPECT_EQ(w1.pairs, 161u - 8u);
  EXPECT_NEAR(w1.trans_m.rmse, 0.25, 1e-12);

  // Sim(3) alignment takes the scale out, so the relative error vanishes too.
  opt.align = AlignMode::kSim3;
  const EvalResult s = evaluateTrajectory(gt, est, opt);
  EXPECT_NEAR(s.alignment.scale, 0.8, 1e-12);
  EXPECT_LT(findStep(s, RpeStep::Kind::kTime, 1.0).trans_m.max, 1e-9);
}

TEST(Rpe, RotationRateGivesKnownRotationError) {
  io::Trajectory gt, est;
  straightLine(1.0, 4.0, gt, est);  // 4 deg/s yaw drift
  EvalOptions opt;
  opt.align = AlignMode::kNone;
  opt.rpe_path_fractions = {};
  opt.rpe_windows_s = {2.0};
  const EvalResult r = evaluateTrajectory(gt, est, opt);
  const RpeResult& w2 = findStep(r, RpeStep::Kind::kTime, 2.0);
  EXPECT_NEAR(w2.rot_deg.min, 8.0, 1e-9);
  EXPECT_NEAR(w2.rot_deg.max, 8.0, 1e-9);
  EXPECT_NEAR(r.ate_rot_deg.max, 4.0 * 20.0, 1e-9);  // the last pose is 80 degrees off
}

TEST(Rpe, PairsAcrossAGapInTheEstimateAreSkipped) {
  io::Trajectory gt, est;
  straightLine(1.25, 0.0, gt, est);
  // Drop 5 s .. 7 s of the estimate (tracking lost).
  std::vector<io::StampedPose> kept;
  for (const auto& p : est.poses) {
    if (p.t_ns <= 5'000'000'000LL || p.t_ns >= 7'000'000'000LL) kept.push_back(p);
  }
  est.poses = kept;
  EvalOptions opt;
  opt.align = AlignMode::kNone;
  opt.rpe_path_fractions = {};
  opt.rpe_distances_m = {1.0};
  opt.rpe_windows_s = {1.0};
  const EvalResult r = evaluateTrajectory(gt, est, opt);
  const RpeResult& w1 = findStep(r, RpeStep::Kind::kTime, 1.0);
  EXPECT_NEAR(w1.trans_m.max, 0.25, 1e-12);  // no stretched pair
  EXPECT_LT(w1.pairs, kept.size() - 8);
  const RpeResult& d1 = findStep(r, RpeStep::Kind::kDistance, 1.0);
  EXPECT_NEAR(d1.trans_m.max, 0.25, 1e-12);
  // The path length counts the ground truth inside the gap.
  EXPECT_DOUBLE_EQ(r.gt_path_length_m, 20.0);
}

TEST(Ate, ConstantOffsetWithoutAlignmentAndZeroAfterIt) {
  io::Trajectory gt = test::lissajous(300, 50'000'000);
  io::Trajectory est = gt;
  for (auto& p : est.poses) p.p_W_X += Eigen::Vector3d(0.3, 0.4, 0.0);
  EvalOptions opt;
  opt.align = AlignMode::kNone;
  EXPECT_NEAR(evaluateTrajectory(gt, est, opt).ate_m.rmse, 0.5, 1e-12);
  opt.align = AlignMode::kSE3;
  const EvalResult r = evaluateTrajectory(gt, est, opt);
  EXPECT_LT(r.ate_m.max, 1e-9);
  EXPECT_EQ(r.over_time.size(), 300u);
}

TEST(Ate, Sim3TransformedEstimateIsRecovered) {
  const io::Trajectory gt = test::lissajous(400, 50'000'000);
  const double s = 0.37;
  const Eigen::Quaterniond R(Eigen::AngleAxisd(1.9, Eigen::Vector3d(1, -2, 0.5).normalized()));
  const io::Trajectory est = test::transformed(gt, s, R, Eigen::Vector3d(4, 5, -6));
  EvalOptions opt;
  opt.align = AlignMode::kSim3;
  const EvalResult r = evaluateTrajectory(gt, est, opt);
  EXPECT_NEAR(r.alignment.scale, 1.0 / s, 1e-9);
  EXPECT_LT(r.ate_m.max, 1e-9);
  EXPECT_LT(r.ate_rot_deg.max, 1e-6);
  for (const auto& e : r.rpe) EXPECT_LT(e.trans_m.max, 1e-9);
  // SE(3) cannot take the scale out.
  opt.align = AlignMode::kSE3;
  EXPECT_GT(evaluateTrajectory(gt, est, opt).ate_m.rmse, 0.1);
}

TEST(Ate, NoAssociatedPairIsAClearError) {
  const io::Trajectory gt = test::lissajous(10, 50'000'000);
  io::Trajectory est = gt;
  for (auto& p : est.poses) p.t_ns += 1'000'000'000'000LL;
  try {
    evaluateTrajectory(gt, est, EvalOptions{});
    FAIL() << "no throw";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("no estimate is within 10.000000 ms of a ground-truth stamp"), std::string::npos)
        << e.what();
  }
}
