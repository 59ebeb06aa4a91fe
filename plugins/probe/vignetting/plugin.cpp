// probe.vignetting: does the run miss a radial fall-off of the irradiance (vignetting)?
//
// Physics: with vignetting V(rho) = 1 + k1 rho^2 + ... (rho the distance from the principal point over
// the half diagonal) the same scene point is brighter near the centre: the residual of a point of host
// intensity I is r = I (V(rho_t) / V(rho_h) - 1) ~ k1 I (rho_t^2 - rho_h^2). The log holds the target's
// radius; after removing the pair's gain and offset ([1, I], what photometric.affine absorbs) the
// regressor x = I rho_t^2 carries k1. The statistic is the cluster-robust score test of k1 = 0, |z|
// (plugins/probe/common/probe_common.h). beta, the one-step estimate of k1, is biased towards 0
// because host and target radii of a point are correlated (a point moves little between keyframes).
#include <cmath>
#include <memory>
#include <sstream>

#include "../common/probe_common.h"
#include "rsvio/plugin/plugin_api.h"

namespace rsvio {
namespace {

const char* kName = "probe.vignetting";

class VignettingProbe : public DiagnosticProbe {
 public:
  explicit VignettingProbe(const Params& p)
      : threshold_(p.getDouble("threshold")), gain_(p.getDouble("estimate_gain")) {}
  std::string effect() const override { return "vignetting"; }

  ProbeResult evaluate(const ProbeInput& in) const override {
    const DiagnosticsLog& log = in.log;
    const nlohmann::json& cfg = in.config;
    if (probe::usesPlugin(cfg, "photometric.vignette"))
      return probe::notApplicable(effect(), "photometric.vignette", "the run models vignetting (photometric.vignette)");
    const auto x_of = [](const ObservationRow& o) {
      return static_cast<double>(o.intensity) * o.radius * o.radius;
    };
    const auto e_of = [](const ObservationRow& o) { return static_cast<double>(o.radius); };
    const probe::PooledResult s = probe::pooledScore(log, x_of, e_of, 2);
    if (s.clusters < 3) return probe::tooLittleData(effect(), "photometric.vignette", s.n, threshold_);
    ProbeResult r;
    r.effect = effect();
    r.plugin = "photometric.vignette";
    // A vignette darkens the border: only a negative k1 is vignetting (a positive one is something else).
    r.statistic = std::max(0.0, -s.z);
    r.threshold = threshold_;
    const double k1 = std::clamp(s.beta * gain_, -0.9, 0.0);
    std::ostringstream line;
    line.precision(3);
    line << "--set photometric.vignette.plugin=photometric.vignette --set photometric.vignette.params.mode=fixed"
         << " --set photometric.vignette.params.initial=[" << k1 << ",0,0]";
    r.config_line = line.str();
    std::ostringstream ex;
    ex.precision(3);
    ex << "residual falls with image radius (z = " << s.z << "), V(rho) ~ 1 + " << k1
       << " rho^2, corner at ~" << 100.0 * (1.0 + k1) << " % of the centre";
    r.explanation = ex.str();
    r.details = probe::toJson(s);
    r.details["k1_one_step"] = s.beta;
    r.details["k1_suggested"] = k1;
    r.details["curve"] = probe::toJson(s.curve, "radius (distance from the principal point / half diagonal)",
                                       "residual (brightness removed per pair)");
    probe::finish(r);
    return r;
  }

 private:
  double threshold_;
  double gain_;
};

ParamTable table() {
  return {paramDouble("threshold", 6.0, 0.0, 1e6, "",
                      "-z of the vignetting score test above which the effect is named (README: false-alarm rate)"),
          paramDouble("estimate_gain", 2.0, 0.0, 100.0, "",
                      "factor from the one-step k1 estimate to the suggested k1 (README: measured)")};
}

void registerAll(PluginRegistrar& r) {
  r.add<DiagnosticProbe>({kName, PluginKind::Probe, "1.0.0",
                          "Vignetting: score test of a radial fall-off (residual against image radius)", table(), ""},
                         [](const Params& p) { return std::make_unique<VignettingProbe>(p); });
}

}  // namespace
}  // namespace rsvio

RSVIO_PLUGIN_ENTRY(rsvio::registerAll)
