// effect.exposure: exposure time / gain changing over time, as an auto-exposure would. Each image's
// linear signal is multiplied by
//     gain(t) = 2^(amplitude_stops * sin(2 pi t / period_s + phase) + jitter_stops * n),   n ~ N(0, 1),
// t the image's stamp (camera clock) in seconds from the start, n drawn per frame. The gain multiplies
// the signal before noise and response; saturation clips later. The per-frame gain is in truth.json
// ("frames"[i].effects.<name>.gain) and nowhere else: it is hidden. The motion-blur window is not changed.
#include <cmath>
#include <memory>

#include "rsvio/interfaces/sim_effect.h"
#include "rsvio/plugin/plugin_api.h"
#include "rsvio/sim/rng.h"

namespace rsvio {
namespace {

ParamTable table() {
  return {paramDouble("amplitude_stops", 1.0, 0.0, 8.0, "stops", "amplitude of the slow change (1 stop = factor 2)"),
          paramDouble("period_s", 8.0, 0.01, 1e5, "s", "period of the slow change"),
          paramDouble("phase_deg", 0.0, -360.0, 360.0, "deg", "phase of the slow change at t = 0"),
          paramDouble("jitter_stops", 0.05, 0.0, 4.0, "stops", "per-frame random change (standard deviation)")};
}

class Exposure : public SimEffect {
 public:
  explicit Exposure(const Params& p)
      : amp_(p.getDouble("amplitude_stops")), period_(p.getDouble("period_s")),
        phase_(p.getDouble("phase_deg") * M_PI / 180.0), jitter_(p.getDouble("jitter_stops")) {}
  int order() const override { return 20; }
  void configure(SimSensorModel& s) override { start_ns_ = s.start_ns; }
  double gain(double t_s, double n) const {
    return std::exp2(amp_ * std::sin(2.0 * M_PI * t_s / period_ + phase_) + jitter_ * n);
  }
  void processImage(cv::Mat& signal, const SimImageContext& ctx, std::mt19937_64& rng) const override {
    const double n = sim::gauss(rng);
    const double g = gain(static_cast<double>(ctx.t_cam_ns - start_ns_) * 1e-9, n);
    signal *= g;
    if (ctx.frame_truth) (*ctx.frame_truth)["gain"] = g;
  }
  nlohmann::json truth() const override {
    return {{"model", "gain(t) = 2^(amplitude_stops * sin(2 pi t / period_s + phase) + jitter_stops * n), n ~ N(0,1) "
                      "per frame, t = stamp - start; multiplies the linear signal"},
            {"amplitude_stops", amp_},
            {"period_s", period_},
            {"phase_rad", phase_},
            {"jitter_stops", jitter_},
            {"per_frame", "frames[i].effects.<name>.gain"}};
  }

 private:
  double amp_, period_, phase_, jitter_;
  int64_t start_ns_ = 0;
};

void registerAll(PluginRegistrar& r) {
  r.add<SimEffect>({"effect.exposure", PluginKind::Effect, "1.0.0",
                    "exposure/gain changing over time, like auto-exposure (hidden: per-frame gains in truth.json)",
                    table()},
                   [](const Params& p) { return std::make_unique<Exposure>(p); });
}

}  // namespace
}  // namespace rsvio

RSVIO_PLUGIN_ENTRY(rsvio::registerAll)
