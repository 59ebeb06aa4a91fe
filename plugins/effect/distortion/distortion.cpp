// effect.distortion: lens distortion of the raw images, radial-tangential (k1 k2 p1 p2) or equidistant
// (k1..k4), Kalibr's conventions. A calibration knows it: the coefficients go to cam0/sensor.yaml
// (distortion_model radial-tangential | equidistant) as well as to truth.json.
#include <memory>

#include "rsvio/core/error.h"
#include "rsvio/interfaces/sim_effect.h"
#include "rsvio/plugin/plugin_api.h"

namespace rsvio {
namespace {

ParamTable table() {
  return {paramEnum("model", "radtan", {"radtan", "equidistant"}, "distortion model"),
          paramArray("radtan_k1_k2_p1_p2", {-0.28, 0.07, 2e-4, -1e-4}, 4, "",
                     "radial-tangential coefficients (used when model = radtan)"),
          paramArray("equidistant_k1_k4", {-0.02, 0.004, -0.002, 0.0005}, 4, "",
                     "equidistant (Kannala-Brandt) coefficients (used when model = equidistant)")};
}

class Distortion : public SimEffect {
 public:
  explicit Distortion(const Params& p) : model_(p.getString("model")) {
    coeffs_ = p.getArray(model_ == "radtan" ? "radtan_k1_k2_p1_p2" : "equidistant_k1_k4");
  }
  int order() const override { return 5; }
  bool inCalibration() const override { return true; }
  void configure(SimSensorModel& s) override {
    s.camera.distortion = model_;
    s.camera.distortion_coeffs = Eigen::Map<const Eigen::VectorXd>(coeffs_.data(), 4);
  }
  nlohmann::json truth() const override { return {{"model", model_}, {"coefficients", coeffs_}}; }

 private:
  std::string model_;
  std::vector<double> coeffs_;
};

void registerAll(PluginRegistrar& r) {
  r.add<SimEffect>({"effect.distortion", PluginKind::Effect, "1.0.0",
                    "lens distortion, radtan or equidistant (in the calibration: cam0/sensor.yaml)", table()},
                   [](const Params& p) { return std::make_unique<Distortion>(p); });
}

}  // namespace
}  // namespace rsvio

RSVIO_PLUGIN_ENTRY(rsvio::registerAll)
