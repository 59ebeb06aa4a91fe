// probe.response: does the run miss a non-linear camera response?
//
// Physics: the affine model assumes target = a * host + b. With a response G the pixel is
// G(k G^-1(I)) for an exposure or vignetting factor k, which is not affine in I unless G is a pure power
// (a gamma curve maps gains to gains, so a pure gamma leaves no trace in photometric residuals).
// What is left is curvature in I: after removing the pair's gain and offset ([1, I]) the regressor
// x = (I / 255)^2 carries it. The statistic is the cluster-robust score test |z|
// (plugins/probe/common/probe_common.h).
#include <cmath>
#include <memory>
#include <sstream>

#include "../common/probe_common.h"
#include "rsvio/plugin/plugin_api.h"

namespace rsvio {
namespace {

const char* kName = "probe.response";

class ResponseProbe : public DiagnosticProbe {
 public:
  explicit ResponseProbe(const Params& p) : threshold_(p.getDouble("threshold")) {}
  std::string effect() const override { return "response"; }

  ProbeResult evaluate(const ProbeInput& in) const override {
    const DiagnosticsLog& log = in.log;
    const nlohmann::json& cfg = in.config;
    if (probe::usesPlugin(cfg, "photometric.response"))
      return probe::notApplicable(effect(), "photometric.response", "the run models the response (photometric.response)");
    const auto x_of = [](const ObservationRow& o) {
      const double i = o.intensity / 255.0;
      return 255.0 * i * i;
    };
    const auto e_of = [](const ObservationRow& o) { return static_cast<double>(o.intensity); };
    const probe::PooledResult s = probe::pooledScore(log, x_of, e_of, 2);
    if (s.clusters < 3) return probe::tooLittleData(effect(), "photometric.response", s.n, threshold_);
    ProbeResult r;
    r.effect = effect();
    r.plugin = "photometric.response";
    r.statistic = std::abs(s.z);
    r.threshold = threshold_;
    // Curvature c of r ~ c 255 (I/255)^2 relative to a gain: a gamma g on the working values bends
    // them by about (g - 1) ln-terms; the suggested gamma is 1 + a first-order estimate, clamped.
    const double g = std::clamp(1.0 - 2.0 * s.beta, 0.3, 3.0);
    std::ostringstream line;
    line.precision(3);
    line << "--set photometric.response.plugin=photometric.response --set photometric.response.params.mode=estimate"
         << " --set photometric.response.params.initial_gamma=" << g;
    r.config_line = line.str();
    std::ostringstream ex;
    ex.precision(3);
    ex << "residual bends with intensity (z = " << s.z << ", curvature " << s.beta
       << "); the back end does not estimate the response yet, so the line records the model and leaves the "
          "images as they are: a calibrated inverse response (pcalib.txt, mode calibrated) applies it";
    r.explanation = ex.str();
    r.details = probe::toJson(s);
    r.details["gamma_suggested"] = g;
    r.details["curve"] = probe::toJson(s.curve, "host intensity", "residual (brightness removed per pair)");
    probe::finish(r);
    return r;
  }

 private:
  double threshold_;
};

ParamTable table() {
  return {paramDouble("threshold", 10.0, 0.0, 1e6, "",
                      "|z| of the curvature score test above which the effect is named (README: false-alarm rate)")};
}

void registerAll(PluginRegistrar& r) {
  r.add<DiagnosticProbe>({kName, PluginKind::Probe, "1.0.0",
                          "Response: score test of curvature in intensity (residual against intensity)", table(), ""},
                         [](const Params& p) { return std::make_unique<ResponseProbe>(p); });
}

}  // namespace
}  // namespace rsvio

RSVIO_PLUGIN_ENTRY(rsvio::registerAll)
