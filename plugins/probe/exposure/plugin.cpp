// probe.exposure: does the run miss a per-frame brightness change (exposure time, gain)?
//
// Physics: when the exposure of the target differs from the host's by a factor k, the residual of a
// point of host intensity I is r = (k - 1) I (+ an offset when the black level moves). For every
// (target, host) pair the probe fits r = b0 + b1 (I - mean I) with the robust weights and tests the
// pair's two coefficients against 0: t^2 = explained energy / the pair's own residual variance, which is
// chi-square with 2 degrees of freedom when the pair has no brightness change. The statistic is the
// fraction of pairs with t^2 above its 99.9 % quantile (13.8); a run without exposure changes has about
// 0.1 % of its pairs there (plus what pose errors put there), one with changing exposure most of them.
#include <cmath>
#include <memory>
#include <sstream>

#include "../common/probe_common.h"
#include "rsvio/plugin/plugin_api.h"

namespace rsvio {
namespace {

const char* kName = "probe.exposure";
constexpr double kChi2_2_999 = 13.8155;

class ExposureProbe : public DiagnosticProbe {
 public:
  explicit ExposureProbe(const Params& p) : threshold_(p.getDouble("threshold")) {}
  std::string effect() const override { return "exposure"; }

  ProbeResult evaluate(const ProbeInput& in) const override {
    const DiagnosticsLog& log = in.log;
    const nlohmann::json& cfg = in.config;
    if (probe::usesPlugin(cfg, "photometric.affine"))
      return probe::notApplicable(effect(), "photometric.affine",
                                  "the run models brightness changes (photometric.affine)");
    const auto cl = probe::clusters(log, 12);
    int64_t t0 = INT64_MAX;
    for (const auto& idx : cl) t0 = std::min(t0, log.observations[idx.front()].t_ns);
    size_t significant = 0, n = 0;
    std::vector<double> t_s, gain, t2s;
    for (const auto& idx : cl) {
      double s0 = 0, s1 = 0, s2 = 0, r0 = 0, r1 = 0, rr = 0, gi = 0, gr = 0;
      for (size_t i : idx) {
        const ObservationRow& o = log.observations[i];
        s0 += o.weight;
        s1 += o.weight * o.intensity;
        r0 += o.weight * o.residual;
        gi += o.weight * static_cast<double>(o.intensity) * o.intensity;
        gr += o.weight * static_cast<double>(o.intensity) * o.residual;
      }
      const double Im = s1 / s0;
      for (size_t i : idx) {
        const ObservationRow& o = log.observations[i];
        const double d = o.intensity - Im;
        s2 += o.weight * d * d;
        r1 += o.weight * d * o.residual;
        rr += o.weight * static_cast<double>(o.residual) * o.residual;
      }
      const double explained = r0 * r0 / s0 + (s2 > 0 ? r1 * r1 / s2 : 0.0);
      const double m = static_cast<double>(idx.size());
      const double rest = std::max(rr - explained, 1e-12);
      // Weighted variance per unit weight: the robust weights sum to about m times their mean.
      const double t2 = explained / (rest / (m - 2.0));
      if (!std::isfinite(t2)) continue;
      ++n;
      if (t2 > kChi2_2_999) ++significant;
      t2s.push_back(t2);
      t_s.push_back(1e-9 * static_cast<double>(log.observations[idx.front()].t_ns - t0));
      gain.push_back(gi > 0 ? gr / gi : 0.0);  // relative brightness change k - 1 of the pair
    }
    if (n < 3) return probe::tooLittleData(effect(), "photometric.affine", n, threshold_);
    ProbeResult r;
    r.effect = effect();
    r.plugin = "photometric.affine";
    r.statistic = static_cast<double>(significant) / static_cast<double>(n);
    r.threshold = threshold_;
    r.config_line = "--set photometric.affine.plugin=photometric.affine";
    std::vector<double> ag;
    for (double g : gain) ag.push_back(std::abs(g));
    std::sort(ag.begin(), ag.end());
    const double med = ag[ag.size() / 2], p90 = ag[static_cast<size_t>(0.9 * (ag.size() - 1))];
    std::ostringstream ex;
    ex.precision(3);
    ex << 100.0 * r.statistic << " % of " << n << " frame pairs change brightness significantly (median |change| "
       << 100.0 * med << " %, 90th percentile " << 100.0 * p90 << " %)";
    r.explanation = ex.str();
    r.details["pairs"] = n;
    r.details["significant_pairs"] = significant;
    r.details["median_abs_change"] = med;
    r.details["p90_abs_change"] = p90;
    // The evidence over time: per target frame, the mean brightness change of its pairs.
    std::map<double, std::pair<double, int>> per_frame;
    for (size_t i = 0; i < t_s.size(); ++i) {
      per_frame[t_s[i]].first += gain[i];
      per_frame[t_s[i]].second += 1;
    }
    std::vector<double> fx, fy;
    for (const auto& [t, g] : per_frame) {
      fx.push_back(t);
      fy.push_back(g.first / g.second);
    }
    r.details["curve"] = {{"x", fx}, {"y", fy}, {"y_name", "brightness change"}, {"x_label", "target keyframe time [s]"},
                          {"y_label", "brightness change, mean over the frame's pairs (target / host - 1)"}};
    probe::finish(r);
    return r;
  }

 private:
  double threshold_;
};

ParamTable table() {
  return {paramDouble("threshold", 0.4, 0.0, 1.0, "",
                      "fraction of frame pairs with a significant brightness change above which the effect is named")};
}

void registerAll(PluginRegistrar& r) {
  r.add<DiagnosticProbe>({kName, PluginKind::Probe, "1.0.0",
                          "Exposure: per-pair brightness change (residual against host intensity, gain and offset)",
                          table(), ""},
                         [](const Params& p) { return std::make_unique<ExposureProbe>(p); });
}

}  // namespace
}  // namespace rsvio

RSVIO_PLUGIN_ENTRY(rsvio::registerAll)
