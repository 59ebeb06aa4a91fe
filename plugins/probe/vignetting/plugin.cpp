// probe.vignetting: does the run miss a radial fall-off of the irradiance (vignetting)?
//
// Physics: with vignetting V(rho) = 1 + k1 rho^2 + k2 rho^4 + k3 rho^6 (rho the distance from the
// principal point over the half diagonal) the same scene point is brighter near the centre: the
// residual of a point of host intensity I seen at host radius rho_h and target radius rho_t is
//   r = I (V(rho_t) / V(rho_h) - 1) ~ k1 I (rho_t^2 - rho_h^2).
// The statistic: after removing the pair's gain and offset ([1, I], what photometric.affine absorbs)
// the regressor x = I (rho_t^2 - rho_h^2) carries k1; the cluster-robust score test of k1 = 0, -z
// (plugins/probe/common/probe_common.h), with the inliers only. Its one-step k1 is biased towards 0
// (the outliers the test leaves out hold the largest vignetting residuals), so it is reported but not
// suggested. Named when both -z / threshold and the fitted corner fall-off / min_falloff exceed 1.
// The estimate suggested: (k1, k2, k3) fitted to the residuals with the full ratio V(rho_t) / V(rho_h)
// (the log's host_radius) and the dropped outliers (rsvio/photometric/vignette_fit.h).
#include <Eigen/Dense>
#include <cmath>
#include <memory>
#include <sstream>

#include "../common/probe_common.h"
#include "rsvio/photometric/vignette_fit.h"
#include "rsvio/plugin/plugin_api.h"

namespace rsvio {
namespace {

const char* kName = "probe.vignetting";

// The run's photometric.vignette slot in mode "fixed": its polynomial (initial, three numbers).
bool fixedVignette(const nlohmann::json& cfg, Eigen::Vector3d* k) {
  if (!cfg.contains("photometric") || !cfg["photometric"].is_object()) return false;
  for (const auto& [key, slot] : cfg["photometric"].items()) {
    if (!slot.is_object() || slot.value("plugin", "") != "photometric.vignette") continue;
    const nlohmann::json params = slot.value("params", nlohmann::json::object());
    if (params.value("mode", "auto") != "fixed") return false;
    const nlohmann::json init = params.value("initial", nlohmann::json::array({0.0, 0.0, 0.0}));
    if (!init.is_array() || init.size() != 3) return false;
    for (int i = 0; i < 3; ++i) {
      if (!init[static_cast<size_t>(i)].is_number()) return false;
      (*k)[i] = init[static_cast<size_t>(i)].get<double>();
    }
    return true;
  }
  return false;
}

class VignettingProbe : public DiagnosticProbe {
 public:
  explicit VignettingProbe(const Params& p)
      : threshold_(p.getDouble("threshold")), min_falloff_(p.getDouble("min_falloff")) {}
  std::string effect() const override { return "vignetting"; }

  ProbeResult evaluate(const ProbeInput& in) const override {
    const DiagnosticsLog& log = in.log;
    const nlohmann::json& cfg = in.config;
    // A run with photometric.vignette in mode "fixed" (the polynomial this probe suggested, applied as a
    // calibration) still gets tested: what its residuals show is the vignetting the polynomial left, and
    // the suggestion is the product of the two, refitted as one polynomial. Any other mode models it.
    Eigen::Vector3d k_run = Eigen::Vector3d::Zero();
    bool refine = false;
    if (probe::usesPlugin(cfg, "photometric.vignette")) {
      if (!fixedVignette(cfg, &k_run))
        return probe::notApplicable(effect(), "photometric.vignette", "the run models vignetting (photometric.vignette)");
      refine = true;
    }
    const auto x_of = [](const ObservationRow& o) {
      return static_cast<double>(o.intensity) * (o.radius * o.radius - o.host_radius * o.host_radius);
    };
    const auto e_of = [](const ObservationRow& o) { return static_cast<double>(o.radius); };
    const probe::PooledResult s = probe::pooledScore(log, x_of, e_of, 2);
    if (s.clusters < 3) return probe::tooLittleData(effect(), "photometric.vignette", s.n, 1.0);
    ProbeResult r;
    r.effect = effect();
    r.plugin = "photometric.vignette";
    r.threshold = 1.0;
    VignetteFit fit = fitVignettePlausible(log.observations);
    // A brightening towards the border is not vignetting (after a fixed polynomial it is an overshoot).
    if (!refine && fit.k[0] > 0.0) fit.k.setZero();
    const Eigen::Vector3d k = refine ? vignetteProduct(k_run, fit.k) : fit.k;
    // Both conditions, each against its own threshold: the score test, -z / threshold (a vignette darkens
    // the border: only a negative z counts), and the fitted fall-off at the corner (what the run's images
    // still lack), (1 - V(1)) / min_falloff; named above 1.
    const double z_part = std::max(0.0, -s.z) / threshold_;
    const double falloff = 1.0 - vignetteValue(fit.k, 1.0);
    r.statistic = std::min(z_part, min_falloff_ > 0 ? std::max(0.0, falloff) / min_falloff_ : INFINITY);
    std::ostringstream line;
    line.precision(3);
    line << "--set photometric.vignette.plugin=photometric.vignette --set photometric.vignette.params.mode=estimate"
         << " --set photometric.vignette.params.initial=[" << k[0] << "," << k[1] << "," << k[2] << "]";
    r.config_line = line.str();
    std::ostringstream ex;
    ex.precision(3);
    ex << "residual falls with image radius (z = " << s.z << "), fitted V(rho) = 1 + " << k[0] << " rho^2 + " << k[1]
       << " rho^4 + " << k[2] << " rho^6, corner at ~" << 100.0 * vignetteValue(k, 1.0) << " % of the centre";
    if (refine)
      ex << " (the run's fixed polynomial, corner at " << 100.0 * vignetteValue(k_run, 1.0)
         << " %, left a corner at " << 100.0 * vignetteValue(fit.k, 1.0) << " %)";
    ex << "; the residuals understate it, the line starts the online estimate there";
    r.explanation = ex.str();
    r.details = probe::toJson(s);
    r.details["k1_one_step"] = s.beta;
    r.details["k_fitted"] = {k[0], k[1], k[2]};
    r.details["fit_params"] = fit.params;
    r.details["fit_iterations"] = fit.iterations;
    r.details["fit_cost_null"] = fit.cost_null;
    r.details["fit_cost"] = fit.cost;
    r.details["corner_ratio"] = vignetteValue(k, 1.0);
    r.details["z_threshold"] = threshold_;
    r.details["falloff"] = falloff;
    r.details["min_falloff"] = min_falloff_;
    if (refine) {
      r.details["k_run"] = {k_run[0], k_run[1], k_run[2]};
      r.details["k_residual"] = {fit.k[0], fit.k[1], fit.k[2]};
    }
    r.details["curve"] = probe::toJson(s.curve, "radius (distance from the principal point / half diagonal)",
                                       "residual (brightness removed per pair)");
    probe::finish(r);
    return r;
  }

 private:
  double threshold_;
  double min_falloff_;
};

ParamTable table() {
  return {paramDouble("threshold", 6.0, 0.0, 1e6, "",
                      "-z of the vignetting score test above which it counts (README: false-alarm rate)"),
          paramDouble("min_falloff", 0.08, 0.0, 1.0, "",
                      "fitted fall-off at the corner (1 - V(1)) above which it counts; named when both count")};
}

void registerAll(PluginRegistrar& r) {
  r.add<DiagnosticProbe>({kName, PluginKind::Probe, "1.0.0",
                          "Vignetting: score test of a radial fall-off (residual against image radius)", table(), ""},
                         [](const Params& p) { return std::make_unique<VignettingProbe>(p); });
}

}  // namespace
}  // namespace rsvio

RSVIO_PLUGIN_ENTRY(rsvio::registerAll)
