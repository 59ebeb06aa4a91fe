// photometric.response: registration and parameter table (the model: response_model.h).
#include <memory>

#include "response_model.h"
#include "rsvio/plugin/plugin_api.h"

namespace rsvio {
namespace {

ParamTable table() {
  return {
      paramEnum("mode", "auto", {"auto", "calibrated", "estimate"},
                "auto: the dataset's inverse response (pcalib.txt) when given, else a gamma the back end does not "
                "estimate yet (the images are left as they are; the run warns)"),
      paramDouble("initial_gamma", 1.0, 0.1, 10.0, "", "initial g of the estimated response G(B) = 255 (B/255)^g"),
  };
}

void registerAll(PluginRegistrar& r) {
  r.add<PhotometricModel>(
      {"photometric.response", PluginKind::Photometric, "1.0.0",
       "Camera response: applies the calibrated inverse response (a gamma to estimate is not used by the back end yet)", table(), ""},
      [](const Params& p) {
        const std::string m = p.getString("mode");
        const ResponseModel::Mode mode = m == "calibrated" ? ResponseModel::Mode::Calibrated
                                         : m == "estimate" ? ResponseModel::Mode::Estimate
                                                           : ResponseModel::Mode::Auto;
        // The slot's path (Params::where() is "<slot>.params"; the model's messages add ".params.<key>").
        std::string where = p.where().empty() ? "photometric.response" : p.where();
        if (where.size() > 7 && where.compare(where.size() - 7, 7, ".params") == 0) where.resize(where.size() - 7);
        return std::make_unique<ResponseModel>(mode, p.getDouble("initial_gamma"), where);
      });
}

}  // namespace
}  // namespace rsvio

RSVIO_PLUGIN_ENTRY(rsvio::registerAll)
