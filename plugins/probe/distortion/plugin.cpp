// probe.distortion: does the run miss (or mis-model) radial lens distortion?
//
// Physics: an error dk1 in the radial distortion moves a pixel along its radius by
// dk1 rho^2 (uv - c) (rho the radius over the half diagonal, c the image centre), so the residual is
// r ~ -dk1 (g . (uv - c)) rho^2 (g the target gradient): residual against radius with the geometric
// signature of a radial shift. The regressor x = -(g . (uv - c)) rho^2; the statistic is the
// cluster-robust score test |z| with the pair's brightness removed (plugins/probe/common/probe_common.h).
// Distortion is a calibration value (camera.pinhole reads it from the calibration's distortion field),
// so the config line points the source at a calibration file that has it.
#include <cmath>
#include <memory>
#include <sstream>

#include "../common/probe_common.h"
#include "rsvio/plugin/plugin_api.h"

namespace rsvio {
namespace {

const char* kName = "probe.distortion";

class DistortionProbe : public DiagnosticProbe {
 public:
  explicit DistortionProbe(const Params& p) : threshold_(p.getDouble("threshold")) {}
  std::string effect() const override { return "distortion"; }

  ProbeResult evaluate(const ProbeInput& in) const override {
    const DiagnosticsLog& log = in.log;
    const double cx = 0.5 * (log.width - 1), cy = 0.5 * (log.height - 1);
    const auto x_of = [cx, cy](const ObservationRow& o) {
      return -(static_cast<double>(o.grad_u) * (o.u - cx) + static_cast<double>(o.grad_v) * (o.v - cy)) * o.radius *
             o.radius;
    };
    const auto e_of = [](const ObservationRow& o) { return static_cast<double>(o.radius); };
    const probe::PooledResult s = probe::pooledScore(log, x_of, e_of, 2);
    if (s.clusters < 3) return probe::tooLittleData(effect(), "camera.pinhole", s.n, threshold_);
    ProbeResult r;
    r.effect = effect();
    r.plugin = "camera.pinhole";
    r.statistic = std::abs(s.z);
    r.threshold = threshold_;
    r.config_line = "--set source.params.calibration_file=<calibration with the lens distortion>";
    std::ostringstream ex;
    ex.precision(3);
    ex << "residual follows a radial pixel shift growing with radius^3 (z = " << s.z << ", dk1 ~ " << s.beta
       << " in half-diagonal units): calibrate the lens (radtan or equidistant)";
    r.explanation = ex.str();
    r.details = probe::toJson(s);
    r.details["dk1_one_step"] = s.beta;
    r.details["curve"] = probe::toJson(s.curve, "radius (distance from the centre / half diagonal)",
                                       "residual (brightness removed per pair)");
    probe::finish(r);
    return r;
  }

 private:
  double threshold_;
};

ParamTable table() {
  return {paramDouble("threshold", 10.0, 0.0, 1e6, "",
                      "|z| of the radial-shift score test above which the effect is named (README: false-alarm rate)")};
}

void registerAll(PluginRegistrar& r) {
  r.add<DiagnosticProbe>({kName, PluginKind::Probe, "1.0.0",
                          "Distortion: score test of a radial pixel shift (residual against radius, gradient along the radius)",
                          table(), ""},
                         [](const Params& p) { return std::make_unique<DistortionProbe>(p); });
}

}  // namespace
}  // namespace rsvio

RSVIO_PLUGIN_ENTRY(rsvio::registerAll)
