// Test-only: its file says motion.misnamed but it registers only motion.somethingelse.
#include "rsvio/interfaces/motion_prior.h"
#include "rsvio/plugin/plugin_api.h"

namespace {
class Nothing : public rsvio::MotionPrior {
 public:
  std::vector<rsvio::SE3d> predict(const std::vector<rsvio::MotionState>&, int64_t) const override { return {}; }
};
void registerAll(rsvio::PluginRegistrar& r) {
  rsvio::PluginInfo info;
  info.name = "motion.somethingelse";
  info.version = "0.0.1";
  info.description = "misnamed";
  r.add<rsvio::MotionPrior>(info, [](const rsvio::Params&) { return std::make_unique<Nothing>(); });
}
}  // namespace
RSVIO_PLUGIN_ENTRY(registerAll)
