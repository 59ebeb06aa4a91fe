// photometric.affine: per-frame affine brightness (a, b) (DSO, Engel et al. 2018, eq. 4; paper sec. IV-A).
// The model adds no image correction; it tells the estimator to optimise (a, b) per frame in
//   r = (I_j[p'] - b_j) - exp(a_j - a_i) (I_i[p] - b_i)
// with priors pulling a and b towards 0 of strength prior_a, prior_b (DSO's setting_affineOptModeA/B:
// 0 = free; DSO uses 1e12 / 1e8, i.e. practically fixed, when a photometric calibration is given).
#include <memory>

#include "rsvio/interfaces/photometric.h"
#include "rsvio/plugin/plugin_api.h"

namespace rsvio {
namespace {

class AffineBrightnessModel : public PhotometricModel {
 public:
  explicit AffineBrightnessModel(const Params& p)
      : prior_a_(p.getDouble("prior_a")), prior_b_(p.getDouble("prior_b")) {}
  bool hasAffineBrightness() const override { return true; }
  double affinePriorA() const override { return prior_a_; }
  double affinePriorB() const override { return prior_b_; }

 private:
  double prior_a_;
  double prior_b_;
};

ParamTable table() {
  return {
      paramDouble("prior_a", 0.0, 0.0, 1e15, "1/unit^2",
                  "information of the prior pulling each frame's a to 0 (0: free; DSO with calibration: 1e12)"),
      paramDouble("prior_b", 0.0, 0.0, 1e15, "1/intensity^2",
                  "information of the prior pulling each frame's b to 0 (0: free; DSO with calibration: 1e8)"),
  };
}

void registerAll(PluginRegistrar& r) {
  r.add<PhotometricModel>({"photometric.affine", PluginKind::Photometric, "1.0.0",
                           "Per-frame affine brightness a, b estimated with the poses (DSO)", table(), ""},
                          [](const Params& p) { return std::make_unique<AffineBrightnessModel>(p); });
}

}  // namespace
}  // namespace rsvio

RSVIO_PLUGIN_ENTRY(rsvio::registerAll)
