// motion.constant_velocity: guesses from the last two frames (uneven intervals included), DSO's recovery
// guesses, the twist prior, and loading through the plugin host with its parameter table.
#include <gtest/gtest.h>

#include "plugins/motion/constant_velocity/constant_velocity.h"
#include "rsvio/config/validate.h"
#include "rsvio/plugin/host.h"

namespace rsvio {
namespace {

MotionState state(int64_t t_ns, const SE3d& T, bool kf = false) {
  MotionState s;
  s.t_ns = t_ns;
  s.T_c_w = T;
  s.is_keyframe = kf;
  return s;
}

Vec6 twist(double tx, double ty, double tz, double rx, double ry, double rz) {
  Vec6 v;
  v << tx, ty, tz, rx, ry, rz;
  return v;
}

TEST(ConstantVelocity, ExtrapolatesWithUnevenFrameIntervals) {
  // True motion: T(t) = exp(v t) T0 with v per second; frames at 0, 50 ms, then predict at 80 ms.
  const Vec6 v = twist(0.3, -0.1, 0.5, 0.2, -0.4, 0.1);
  const SE3d T0 = SE3d::exp(twist(1, 2, 3, 0.1, 0.2, 0.3));
  const std::vector<MotionState> h = {state(0, T0), state(50'000'000, SE3d::exp(v * 0.05) * T0)};
  ConstantVelocityPrior p({false, 0.04, 0, 0});
  const auto g = p.predict(h, 80'000'000);
  ASSERT_EQ(g.size(), 1u);
  EXPECT_TRUE(g[0].isApprox(SE3d::exp(v * 0.08) * T0, 1e-9));
  EXPECT_TRUE(ConstantVelocityPrior::velocity(h[0], h[1]).isApprox(v, 1e-9));
}

TEST(ConstantVelocity, RecoveryGuessesFollowDso) {
  const Vec6 v = twist(0.3, 0, 0, 0, 0.2, 0);
  const SE3d T0 = SE3d::exp(twist(0, 0, 1, 0, 0, 0));
  const SE3d T1 = SE3d::exp(v * 0.05) * T0;
  const std::vector<MotionState> h = {state(0, T0, true), state(50'000'000, T1)};
  ConstantVelocityPrior p({true, 0.04, 0, 0});
  const auto g = p.predict(h, 100'000'000);
  ASSERT_EQ(g.size(), 5u + 26u);
  EXPECT_TRUE(g[0].isApprox(SE3d::exp(v * 0.05) * T1, 1e-9));   // constant velocity
  EXPECT_TRUE(g[1].isApprox(SE3d::exp(v * 0.10) * T1, 1e-9));   // double
  EXPECT_TRUE(g[2].isApprox(SE3d::exp(v * 0.025) * T1, 1e-9));  // half
  EXPECT_TRUE(g[3].isApprox(T1, 1e-12));                        // no motion
  EXPECT_TRUE(g[4].isApprox(T0, 1e-12));                        // last keyframe
  for (size_t i = 5; i < g.size(); ++i) {
    const Vec6 d = (g[i] * g[0].inverse()).log();
    EXPECT_NEAR(d.head<3>().norm(), 0.0, 1e-12);  // rotation about the new camera centre
    const double n = d.tail<3>().norm();
    const double expected_axes = std::round(n * n / (0.04 * 0.04));
    EXPECT_NEAR(n * n / (0.04 * 0.04), expected_axes, 1e-9);
    EXPECT_GE(expected_axes, 1);
    EXPECT_LE(expected_axes, 3);
  }
}

TEST(ConstantVelocity, ShortHistories) {
  ConstantVelocityPrior p;
  EXPECT_TRUE(p.predict({}, 0).empty());
  const SE3d T = SE3d::exp(twist(1, 0, 0, 0, 0, 0.1));
  const auto g = p.predict({state(0, T)}, 50'000'000);
  ASSERT_EQ(g.size(), 1u + 26u);
  EXPECT_TRUE(g[0].isApprox(T, 1e-12));
}

TEST(ConstantVelocity, HistoryTwistPriorIsTheVelocityAroundTheKeyframe) {
  const Vec6 v = twist(0.2, 0.1, -0.3, 0.05, 0.1, -0.2);
  const SE3d T0 = SE3d::exp(twist(0.5, 0, 0, 0, 0.3, 0));
  std::vector<MotionState> h;
  for (int i = 0; i < 4; ++i) h.push_back(state(i * 40'000'000LL, SE3d::exp(v * (0.04 * i)) * T0, i == 2));
  TwistPrior prior;
  EXPECT_FALSE(ConstantVelocityPrior().twistPrior(h, h[2], &prior));  // weights 0: no opinion
  ConstantVelocityPrior p({true, 0.04, 10.0, 100.0, /*twist_prior_in_window=*/false});
  EXPECT_FALSE(p.smoothMotionInformation(nullptr));  // "history": no term in the window
  ASSERT_TRUE(p.twistPrior(h, h[2], &prior));
  EXPECT_TRUE(prior.mean.isApprox(v, 1e-9));
  EXPECT_DOUBLE_EQ(prior.information(0, 0), 10.0);
  EXPECT_DOUBLE_EQ(prior.information(5, 5), 100.0);
  EXPECT_DOUBLE_EQ(prior.information(0, 1), 0.0);
  ASSERT_TRUE(p.twistPrior(h, h[3], &prior));  // last frame: one-sided
  EXPECT_TRUE(prior.mean.isApprox(v, 1e-9));
  EXPECT_FALSE(p.twistPrior({h[0]}, h[0], &prior));
}

TEST(ConstantVelocity, WindowTwistPriorHandsItsInformationToTheBackEnd) {
  const Vec6 v = twist(0.2, 0.1, -0.3, 0.05, 0.1, -0.2);
  std::vector<MotionState> h;
  for (int i = 0; i < 4; ++i) h.push_back(state(i * 40'000'000LL, SE3d::exp(v * (0.04 * i)), i == 2));
  const ConstantVelocityPrior p({true, 0.04, 10.0, 100.0, /*twist_prior_in_window=*/true});
  TwistPrior prior;
  EXPECT_FALSE(p.twistPrior(h, h[2], &prior));  // no fixed mean: the back end ties the twist to the poses
  Mat6 info;
  ASSERT_TRUE(p.smoothMotionInformation(&info));
  EXPECT_DOUBLE_EQ(info(0, 0), 10.0);
  EXPECT_DOUBLE_EQ(info(2, 2), 10.0);
  EXPECT_DOUBLE_EQ(info(3, 3), 100.0);
  EXPECT_DOUBLE_EQ(info(0, 3), 0.0);
  EXPECT_FALSE(ConstantVelocityPrior().smoothMotionInformation(&info));  // weights 0: none
}

TEST(ConstantVelocity, LoadsThroughTheHostWithItsParamTable) {
  PluginHost host({RSVIO_PLUGIN_DIR});
  const PluginInfo& info = host.info("motion.constant_velocity");
  EXPECT_EQ(info.kind, PluginKind::Motion);
  std::vector<ConfigProblem> problems;
  const auto params = validateParams(nlohmann::json{{"recovery", false}}, info.params, "motion.cv.params", problems);
  ASSERT_TRUE(problems.empty());
  EXPECT_DOUBLE_EQ(params["recovery_rotation_rad"].get<double>(), 0.04);
  auto prior = host.create<MotionPrior>("motion.constant_velocity", Params(params));
  EXPECT_EQ(prior->predict({state(0, SE3d())}, 1).size(), 1u);
  problems.clear();
  validateParams(nlohmann::json{{"recovery_rotation_rad", 2.0}}, info.params, "motion.cv.params", problems);
  EXPECT_EQ(problems.size(), 1u);
}

}  // namespace
}  // namespace rsvio
