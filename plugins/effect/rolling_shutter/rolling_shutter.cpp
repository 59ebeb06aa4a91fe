// effect.rolling_shutter: rows are read one after another, `line_delay_us` apart.
// Row r of an image stamped at row y0 = (h - 1) / 2 is read at t + (r - y0) * line_delay (top_down) or
// t + (y0 - r) * line_delay (bottom_up); the renderer uses that row's exact pose. Hidden: the line
// delay is in truth.json only (a calibration in global-shutter mode would not know it).
#include <memory>

#include "rsvio/interfaces/sim_effect.h"
#include "rsvio/plugin/plugin_api.h"

namespace rsvio {
namespace {

ParamTable table() {
  return {paramDouble("line_delay_us", 58.94, 0.0, 10000.0, "us",
                      "time between consecutive rows (the paper's 29.47 us at 1024 rows is 58.94 us at 512)"),
          paramEnum("readout", "top_down", {"top_down", "bottom_up"}, "direction in which rows are read")};
}

class RollingShutter : public SimEffect {
 public:
  explicit RollingShutter(const Params& p)
      : line_delay_s_(p.getDouble("line_delay_us") * 1e-6), readout_(p.getString("readout")) {}
  int order() const override { return 10; }
  void configure(SimSensorModel& s) override {
    s.line_delay_s = line_delay_s_;
    s.readout = readout_;
    rows_ = s.camera.height;
  }
  nlohmann::json truth() const override {
    return {{"line_delay_s", line_delay_s_},
            {"readout", readout_},
            {"readout_time_s", line_delay_s_ * (rows_ - 1)},
            {"row_time", "t_row = t_image + (r - y0) * line_delay_s (top_down) or (y0 - r) * line_delay_s (bottom_up), "
                         "y0 = (height - 1) / 2"}};
  }

 private:
  double line_delay_s_;
  std::string readout_;
  int rows_ = 0;
};

void registerAll(PluginRegistrar& r) {
  r.add<SimEffect>({"effect.rolling_shutter", PluginKind::Effect, "1.0.0",
                    "rolling shutter: rows read line_delay_us apart (hidden: truth.json only)", table()},
                   [](const Params& p) { return std::make_unique<RollingShutter>(p); });
}

}  // namespace
}  // namespace rsvio

RSVIO_PLUGIN_ENTRY(rsvio::registerAll)
