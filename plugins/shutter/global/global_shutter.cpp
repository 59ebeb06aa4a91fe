// shutter.global: every row is read at the image timestamp (rowTime = 0). The rolling-shutter
// projection (rsvio/geometry/rs_projection.h) then reduces to one ordinary projection.
#include <memory>

#include "rsvio/interfaces/shutter.h"
#include "rsvio/plugin/plugin_api.h"

namespace rsvio {
namespace {

class GlobalShutter : public ShutterModel {
 public:
  void setCalibration(const CameraCalibration&) override {}
  bool isRolling() const override { return false; }
  double rowTime(double) const override { return 0.0; }
  double rowTimeDerivative() const override { return 0.0; }
  double lineDelay() const override { return 0.0; }
  void setLineDelay(double) override {}  // a global shutter has no line delay to estimate
};

void registerAll(PluginRegistrar& r) {
  r.add<ShutterModel>({"shutter.global", PluginKind::Shutter, "1.0.0",
                       "Global shutter: every row is captured at the image timestamp", {}, ""},
                      [](const Params&) { return std::make_unique<GlobalShutter>(); });
}

}  // namespace
}  // namespace rsvio

RSVIO_PLUGIN_ENTRY(rsvio::registerAll)
