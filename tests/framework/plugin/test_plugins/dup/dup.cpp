// Test-only: registers its own name and also "motion.testonly", which the good test plugin owns.
#include "rsvio/interfaces/motion_prior.h"
#include "rsvio/plugin/plugin_api.h"

namespace {
class Nothing : public rsvio::MotionPrior {
 public:
  std::vector<rsvio::SE3d> predict(const std::vector<rsvio::MotionState>&, int64_t) const override { return {}; }
};
void registerAll(rsvio::PluginRegistrar& r) {
  for (const char* name : {"motion.dup", "motion.testonly"}) {
    rsvio::PluginInfo info;
    info.name = name;
    info.version = "0.0.1";
    info.description = "duplicate";
    r.add<rsvio::MotionPrior>(info, [](const rsvio::Params&) { return std::make_unique<Nothing>(); });
  }
}
}  // namespace
RSVIO_PLUGIN_ENTRY(registerAll)
