// effect.vignette: radial fall-off of the irradiance, V(r) = 1 + k1 r^2 + k2 r^4 + k3 r^6, multiplied
// into the linear signal. r is the distance from the principal point divided by the distance from the
// principal point to the farthest image corner, so V(1) = 1 + k1 + k2 + k3 is the corner-to-centre ratio
// at that corner. Hidden: truth.json only (a photometric calibration would be needed to know it).
#include <cmath>
#include <memory>
#include <opencv2/core.hpp>

#include "rsvio/core/error.h"
#include "rsvio/interfaces/sim_effect.h"
#include "rsvio/plugin/plugin_api.h"

namespace rsvio {
namespace {

ParamTable table() {
  return {paramDouble("k1", -0.3, -10.0, 10.0, "", "coefficient of r^2"),
          paramDouble("k2", -0.15, -10.0, 10.0, "", "coefficient of r^4"),
          paramDouble("k3", -0.05, -10.0, 10.0, "", "coefficient of r^6")};
}

class Vignette : public SimEffect {
 public:
  explicit Vignette(const Params& p) : k1_(p.getDouble("k1")), k2_(p.getDouble("k2")), k3_(p.getDouble("k3")) {
    for (int i = 0; i <= 100; ++i)
      if (!(value(i / 100.0) > 0.0))
        throw ConfigError("effects.vignette.params: V(r) = 1 + k1 r^2 + k2 r^4 + k3 r^6 must stay positive on [0, 1]");
  }
  int order() const override { return 10; }
  double value(double r) const {
    const double r2 = r * r;
    return 1.0 + r2 * (k1_ + r2 * (k2_ + r2 * k3_));
  }
  void configure(SimSensorModel& s) override {
    const CameraCalibration& c = s.camera;
    cx_ = c.intrinsics[2];
    cy_ = c.intrinsics[3];
    const double dx = std::max(cx_, c.width - 1 - cx_), dy = std::max(cy_, c.height - 1 - cy_);
    r_max_ = std::hypot(dx, dy);
    map_.create(c.height, c.width, CV_32F);
    for (int y = 0; y < c.height; ++y)
      for (int x = 0; x < c.width; ++x) map_.at<float>(y, x) = static_cast<float>(value(std::hypot(x - cx_, y - cy_) / r_max_));
  }
  void processImage(cv::Mat& signal, const SimImageContext&, std::mt19937_64&) const override {
    cv::multiply(signal, map_, signal);
  }
  nlohmann::json truth() const override {
    return {{"model", "V(r) = 1 + k1 r^2 + k2 r^4 + k3 r^6, multiplies the irradiance"},
            {"k1", k1_},
            {"k2", k2_},
            {"k3", k3_},
            {"centre_px", {cx_, cy_}},
            {"r_normaliser_px", r_max_},
            {"corner_ratio", value(1.0)}};
  }

 private:
  double k1_, k2_, k3_;
  double cx_ = 0, cy_ = 0, r_max_ = 1;
  cv::Mat map_;
};

void registerAll(PluginRegistrar& r) {
  r.add<SimEffect>({"effect.vignette", PluginKind::Effect, "1.0.0",
                    "radial vignetting V(r) = 1 + k1 r^2 + k2 r^4 + k3 r^6 (hidden)", table()},
                   [](const Params& p) { return std::make_unique<Vignette>(p); });
}

}  // namespace
}  // namespace rsvio

RSVIO_PLUGIN_ENTRY(rsvio::registerAll)
