// Test-only motion prior: predicts the last pose shifted by `step_m` along x.
#include "rsvio/interfaces/motion_prior.h"
#include "rsvio/plugin/plugin_api.h"

namespace {
class TestOnlyPrior : public rsvio::MotionPrior {
 public:
  explicit TestOnlyPrior(const rsvio::Params& p) : step_(p.getDouble("step_m")) {}
  std::vector<rsvio::SE3d> predict(const std::vector<rsvio::MotionState>& history, int64_t) const override {
    rsvio::SE3d T = history.empty() ? rsvio::SE3d() : history.back().T_c_w;
    return {rsvio::SE3d(rsvio::SO3d(), Eigen::Vector3d(step_, 0, 0)) * T};
  }

 private:
  double step_;
};

void registerAll(rsvio::PluginRegistrar& r) {
  rsvio::PluginInfo info;
  info.name = "motion.testonly";
  info.version = "0.0.1";
  info.description = "test-only prior";
  info.params = {rsvio::paramDouble("step_m", 0.5, 0.0, 10.0, "m", "shift per prediction"),
                 rsvio::paramEnum("mode", "fast", {"fast", "slow"}, "a choice"),
                 rsvio::paramInt("count", 3, 1, 9, "", "an integer")};
  r.add<rsvio::MotionPrior>(info, [](const rsvio::Params& p) { return std::make_unique<TestOnlyPrior>(p); });
}
}  // namespace

RSVIO_PLUGIN_ENTRY(registerAll)
