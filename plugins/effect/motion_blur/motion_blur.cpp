// effect.motion_blur: each row integrates light over its exposure, centred on the row's read time:
// [t_row - exposure / 2, t_row + exposure / 2]. The renderer averages `samples` poses spread evenly over
// that window (stratified with the spatial supersampling). Hidden: truth.json only.
#include <memory>

#include "rsvio/interfaces/sim_effect.h"
#include "rsvio/plugin/plugin_api.h"

namespace rsvio {
namespace {

ParamTable table() {
  return {paramDouble("exposure_ms", 8.0, 0.0, 100.0, "ms", "exposure time of each row"),
          paramInt("samples", 8, 1, 64, "", "time samples across the exposure (more is smoother and slower)")};
}

class MotionBlur : public SimEffect {
 public:
  explicit MotionBlur(const Params& p)
      : exposure_s_(p.getDouble("exposure_ms") * 1e-3), samples_(static_cast<int>(p.getInt("samples"))) {}
  int order() const override { return 10; }
  void configure(SimSensorModel& s) override {
    s.exposure_s = exposure_s_;
    s.blur_samples = samples_;
  }
  nlohmann::json truth() const override {
    return {{"exposure_s", exposure_s_},
            {"samples", samples_},
            {"window", "row r integrates over [t_row - exposure_s / 2, t_row + exposure_s / 2]"}};
  }

 private:
  double exposure_s_;
  int samples_;
};

void registerAll(PluginRegistrar& r) {
  r.add<SimEffect>({"effect.motion_blur", PluginKind::Effect, "1.0.0",
                    "motion blur from the exposure time, centred on each row's read time (hidden)", table()},
                   [](const Params& p) { return std::make_unique<MotionBlur>(p); });
}

}  // namespace
}  // namespace rsvio

RSVIO_PLUGIN_ENTRY(rsvio::registerAll)
