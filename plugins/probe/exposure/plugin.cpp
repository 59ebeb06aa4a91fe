// probe.exposure: does the run miss a per-frame brightness change (exposure time, gain)?
//
// Physics: when the exposure of the target differs from the host's by a factor k, the residual of a
// point of host intensity I is r = (k - 1) I (+ an offset when the black level moves). For every
// (target, host) pair the probe fits r = b0 + b1 (I - mean I) with the robust weights and tests the
// pair's two coefficients against 0: t^2 = explained energy / the pair's own residual variance, which is
// chi-square with 2 degrees of freedom when the pair has no brightness change. The statistic is the
// fraction of pairs with t^2 above its 99.9 % quantile (13.8); a run without exposure changes has about
// 0.1 % of its pairs there (plus what pose errors put there), one with changing exposure most of them.
// The monocular start's corner steps (the log's track rows: each corner's 3x3 mean intensity in two
// consecutive frames, before any window exists) are pairs of the same kind, with the intensity change
// as the residual and Huber weights: a run that fails in its first window, as one with an unmodelled
// exposure change can, still has them (docs/diagnose.md, "Exposure from the start's corners").
#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <sstream>

#include "../common/probe_common.h"
#include "rsvio/plugin/plugin_api.h"

namespace rsvio {
namespace {

const char* kName = "probe.exposure";
constexpr double kChi2_2_999 = 13.8155;

struct PairSample {
  double intensity, residual, weight;  // host (previous) intensity, residual, robust weight
};
struct PairFit {
  bool ok = false;
  double t2 = 0.0;    // explained energy over the pair's residual variance (chi-square, 2 dof, without a change)
  double gain = 0.0;  // relative brightness change k - 1 (through the origin)
};

// r = b0 + b1 (I - mean I) with the weights; t^2 of (b0, b1) against 0.
PairFit fitPair(const std::vector<PairSample>& ps) {
  double s0 = 0, s1 = 0, s2 = 0, r0 = 0, r1 = 0, rr = 0, gi = 0, gr = 0;
  for (const auto& p : ps) {
    s0 += p.weight;
    s1 += p.weight * p.intensity;
    r0 += p.weight * p.residual;
    gi += p.weight * p.intensity * p.intensity;
    gr += p.weight * p.intensity * p.residual;
  }
  PairFit f;
  if (!(s0 > 0)) return f;
  const double Im = s1 / s0;
  for (const auto& p : ps) {
    const double d = p.intensity - Im;
    s2 += p.weight * d * d;
    r1 += p.weight * d * p.residual;
    rr += p.weight * p.residual * p.residual;
  }
  const double explained = r0 * r0 / s0 + (s2 > 0 ? r1 * r1 / s2 : 0.0);
  const double m = static_cast<double>(ps.size());
  const double rest = std::max(rr - explained, 1e-12);
  // Weighted variance per unit weight: the robust weights sum to about m times their mean.
  f.t2 = explained / (rest / (m - 2.0));
  f.gain = gi > 0 ? gr / gi : 0.0;
  f.ok = std::isfinite(f.t2);
  return f;
}

// Huber weights (k = 1.345 robust sigmas, sigma from the median absolute deviation about the median):
// a corner whose track slipped must not make its step's change.
void huberWeights(std::vector<PairSample>* ps) {
  std::vector<double> r;
  for (const auto& p : *ps) r.push_back(p.residual);
  std::nth_element(r.begin(), r.begin() + r.size() / 2, r.end());
  const double med = r[r.size() / 2];
  for (double& x : r) x = std::abs(x - med);
  std::nth_element(r.begin(), r.begin() + r.size() / 2, r.end());
  const double k = 1.345 * std::max(1.4826 * r[r.size() / 2], 1e-3);
  for (auto& p : *ps) {
    const double a = std::abs(p.residual - med);
    p.weight = a <= k ? 1.0 : k / a;
  }
}

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
    for (const TrackRow& t : log.tracks) t0 = std::min(t0, t.t_ns);
    size_t significant = 0, n = 0, start_pairs = 0, start_significant = 0;
    std::vector<double> t_s, gain;
    auto add = [&](const PairFit& f, int64_t t_ns, bool start) {
      if (!f.ok) return;
      ++n;
      const bool sig = f.t2 > kChi2_2_999;
      significant += sig;
      if (start) {
        ++start_pairs;
        start_significant += sig;
      }
      t_s.push_back(1e-9 * static_cast<double>(t_ns - t0));
      gain.push_back(f.gain);
    };
    std::vector<PairSample> ps;
    for (const auto& idx : cl) {
      ps.clear();
      for (size_t i : idx) {
        const ObservationRow& o = log.observations[i];
        ps.push_back({o.intensity, o.residual, o.weight});
      }
      add(fitPair(ps), log.observations[idx.front()].t_ns, false);
    }
    // The monocular start's corner steps (frame to frame, before any window): the residual of the
    // brightness-constancy model is the step's intensity change; Huber weights as the window's.
    std::map<std::pair<int32_t, int32_t>, std::vector<const TrackRow*>> steps;
    for (const TrackRow& t : log.tracks)
      if (std::isfinite(t.intensity) && std::isfinite(t.intensity_prev)) steps[{t.frame, t.prev_frame}].push_back(&t);
    for (const auto& [key, rows] : steps) {
      if (rows.size() < 12) continue;
      ps.clear();
      for (const TrackRow* t : rows) ps.push_back({t->intensity_prev, t->intensity - t->intensity_prev, 1.0});
      huberWeights(&ps);
      add(fitPair(ps), rows.front()->t_ns, true);
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
       << 100.0 * med << " %, 90th percentile " << 100.0 * p90 << " %";
    if (start_pairs > 0) ex << "; " << start_significant << " of the start's " << start_pairs << " corner steps";
    ex << ")";
    r.explanation = ex.str();
    r.details["pairs"] = n;
    r.details["significant_pairs"] = significant;
    r.details["start_pairs"] = start_pairs;
    r.details["start_significant_pairs"] = start_significant;
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
