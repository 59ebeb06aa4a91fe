// photometric.vignette: registration and parameter table (the model: vignette_model.h).
#include <memory>

#include "rsvio/plugin/plugin_api.h"
#include "vignette_model.h"

namespace rsvio {
namespace {

ParamTable table() {
  return {
      paramEnum("mode", "auto", {"auto", "calibrated", "estimate", "fixed"},
                "auto: the dataset's vignette.png when given, else estimate a radial polynomial online; "
                "fixed: divide by the polynomial `initial` as a calibration"),
      paramDouble("min_value", 0.05, 1e-3, 1.0, "", "vignette values are clamped to this before dividing"),
      paramArray("initial", {0.0, 0.0, 0.0}, 3, "", "v1 v2 v3 of V(r) = 1 + v1 r^2 + v2 r^4 + v3 r^6 to start from (estimate) or to divide by (fixed)"),
      paramInt("min_rows", 3000, 100, 100000000, "",
               "estimate: residuals (observations that left the window) needed before each refinement"),
      paramDouble("min_gain", 0.05, 0.0, 1.0, "",
                  "estimate: a refinement is applied when it explains at least this fraction of the residual energy"),
  };
}

void registerAll(PluginRegistrar& r) {
  r.add<PhotometricModel>(
      {"photometric.vignette", PluginKind::Photometric, "1.0.0",
       "Vignetting: divides by the calibrated vignette, or estimates a radial polynomial online", table(), ""},
      [](const Params& p) {
        const std::string m = p.getString("mode");
        const VignetteModel::Mode mode = m == "calibrated" ? VignetteModel::Mode::Calibrated
                                         : m == "estimate" ? VignetteModel::Mode::Estimate
                                         : m == "fixed"    ? VignetteModel::Mode::Fixed
                                                           : VignetteModel::Mode::Auto;
        const std::vector<double> v = p.getArray("initial");
        // The slot's path (Params::where() is "<slot>.params"; the model's messages add ".params.<key>").
        std::string where = p.where().empty() ? "photometric.vignette" : p.where();
        if (where.size() > 7 && where.compare(where.size() - 7, 7, ".params") == 0) where.resize(where.size() - 7);
        return std::make_unique<VignetteModel>(mode, p.getDouble("min_value"), Eigen::Vector3d(v[0], v[1], v[2]),
                                               where, static_cast<size_t>(p.getInt("min_rows")),
                                               p.getDouble("min_gain"));
      });
}

}  // namespace
}  // namespace rsvio

RSVIO_PLUGIN_ENTRY(rsvio::registerAll)
