// probe.rolling_shutter: does the run miss a rolling shutter?
//
// Physics: with a rolling shutter row `row` (raw row minus y0) is read `row * d` seconds after the
// image time (d the line delay). A point moving at pixel velocity vel [px/s] then lies at
// uv + vel * row * d, and the global-shutter model's residual is r = I_t(uv) - I_h ~ -(g . vel) row d
// (g the target image gradient). The regressor x = -(g . vel) * row is the residual per unit line delay;
// the probe's statistic is the cluster-robust score test of d = 0 (plugins/probe/common/probe_common.h)
// with the pair's brightness removed, |z|. beta, the line delay's one-step estimate [s per row], is far
// too small (the bundle adjustment absorbs most of it) and gives only the readout direction; the
// suggested value comes from the frame period (see README).
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <sstream>

#include "../common/probe_common.h"
#include "rsvio/plugin/plugin_api.h"

namespace rsvio {
namespace {

const char* kName = "probe.rolling_shutter";

// Pixel velocity of one keyframe as a quadratic field over the image (exact for rotation, smooth for
// translation over a scene of similar depths).
struct FlowField {
  Eigen::Matrix<double, 6, 2> C = Eigen::Matrix<double, 6, 2>::Zero();
  double cx = 0, cy = 0, s = 1;
  Eigen::Matrix<double, 6, 1> basis(double u, double v) const {
    const double a = (u - cx) * s, b = (v - cy) * s;
    Eigen::Matrix<double, 6, 1> p;
    p << 1, a, b, a * a, a * b, b * b;
    return p;
  }
  Eigen::Vector2d at(double u, double v) const { return C.transpose() * basis(u, v); }
};

// Median time between consecutive frames, from the keyframes' stamps and sequence indices (0: unknown).
double framePeriod(const DiagnosticsLog& log) {
  std::map<int32_t, int64_t> t;
  for (const auto& o : log.observations) t.emplace(o.frame, o.t_ns);
  std::vector<double> p;
  for (auto it = t.begin(); it != t.end() && std::next(it) != t.end(); ++it) {
    const auto nx = std::next(it);
    if (nx->first > it->first) p.push_back(1e-9 * static_cast<double>(nx->second - it->second) / (nx->first - it->first));
  }
  if (p.empty()) return 0.0;
  std::nth_element(p.begin(), p.begin() + p.size() / 2, p.end());
  return p[p.size() / 2] > 0 ? p[p.size() / 2] : 0.0;
}

std::map<int32_t, FlowField> fitFlowFields(const DiagnosticsLog& log) {
  std::map<int32_t, Eigen::Matrix<double, 6, 6>> A;
  std::map<int32_t, Eigen::Matrix<double, 6, 2>> B;
  std::map<int32_t, int> n;
  FlowField proto;
  proto.cx = 0.5 * (log.width - 1);
  proto.cy = 0.5 * (log.height - 1);
  proto.s = 2.0 / std::max(1, std::max(log.width, log.height));
  for (const auto& o : log.observations) {
    if (!probe::usable(o)) continue;
    const auto p = proto.basis(o.u, o.v);
    auto& a = A.try_emplace(o.frame, Eigen::Matrix<double, 6, 6>::Zero()).first->second;
    auto& b = B.try_emplace(o.frame, Eigen::Matrix<double, 6, 2>::Zero()).first->second;
    a += p * p.transpose();
    b += p * Eigen::RowVector2d(o.vel_u, o.vel_v);
    ++n[o.frame];
  }
  std::map<int32_t, FlowField> out;
  for (auto& [f, a] : A) {
    if (n[f] < 30) continue;
    FlowField ff = proto;
    ff.C = (a + 1e-9 * a.trace() * Eigen::Matrix<double, 6, 6>::Identity()).ldlt().solve(B[f]);
    if (ff.C.allFinite()) out[f] = ff;
  }
  return out;
}

class RollingShutterProbe : public DiagnosticProbe {
 public:
  explicit RollingShutterProbe(const Params& p)
      : threshold_(p.getDouble("threshold")),
        gain_(p.getDouble("estimate_gain")),
        clip_(p.getDouble("clip")),
        readout_fraction_(p.getDouble("readout_fraction")) {}
  std::string effect() const override { return "rolling_shutter"; }

  ProbeResult evaluate(const ProbeInput& in) const override {
    const DiagnosticsLog& log = in.log;
    const nlohmann::json& cfg = in.config;
    if (probe::usesPlugin(cfg, "shutter.rolling") || log.line_delay_s > 0)
      return probe::notApplicable(effect(), "shutter.rolling", "the run models a rolling shutter (shutter.rolling)");
    // The host's own rolling shutter displaced the point the model back-projected: what the residual
    // sees is the difference of the two displacements, (vel_target - vel_host) * row * d (rows of a
    // point differ little between neighbouring keyframes). The host's pixel velocity at the point is
    // taken from a smooth flow field fitted to the velocities logged with the host as target.
    const std::map<int32_t, FlowField> flow = fitFlowFields(log);
    const auto rel_vel = [&flow](const ObservationRow& o) -> Eigen::Vector2d {
      Eigen::Vector2d v(o.vel_u, o.vel_v);
      const auto it = flow.find(o.host);
      if (it == flow.end()) return Eigen::Vector2d(std::nan(""), std::nan(""));
      return v - it->second.at(o.u, o.v);
    };
    const auto raw_x = [&rel_vel](const ObservationRow& o) {
      const Eigen::Vector2d dv = rel_vel(o);
      return -(o.grad_u * dv.x() + o.grad_v * dv.y()) * o.row;
    };
    // The regressor is clipped at a few times its median magnitude: the bundle adjustment absorbs most
    // of a rolling shutter where it is largest (fast motion, strong gradients, far rows) and the robust
    // weights cut those residuals, so the unclipped regressor's tail would decide the test alone.
    std::vector<double> mags;
    for (const auto& o : log.observations)
      if (probe::usable(o)) {
        const double x = raw_x(o);
        if (std::isfinite(x)) mags.push_back(std::abs(x));
      }
    double clip = 0;
    if (!mags.empty()) {
      std::nth_element(mags.begin(), mags.begin() + mags.size() / 2, mags.end());
      clip = clip_ * mags[mags.size() / 2];
    }
    const auto x_of = [&raw_x, clip](const ObservationRow& o) {
      const double x = raw_x(o);
      return clip > 0 ? std::clamp(x, -clip, clip) : x;
    };
    const auto e_of = [&rel_vel](const ObservationRow& o) {
      const Eigen::Vector2d dv = rel_vel(o);
      return -(o.grad_u * dv.x() + o.grad_v * dv.y()) * o.row * 1e-6;
    };
    const probe::PooledResult s = probe::pooledScore(log, x_of, e_of, 2);
    if (s.clusters < 3) return probe::tooLittleData(effect(), "shutter.rolling", s.n, threshold_);
    ProbeResult r;
    r.effect = effect();
    r.plugin = "shutter.rolling";
    r.statistic = std::abs(s.z);
    r.threshold = threshold_;
    // The one-step value is far below the true line delay (the global-shutter bundle adjustment absorbs
    // most of a rolling shutter into poses and depths: 0.4-0.7 us measured for a true 117.9 us), so it
    // gives the readout direction, not the value. The suggested line delay is readout_fraction of the
    // frame period over the rows (the readout cannot be longer than the frame period; CMOS sensors read
    // out in most of it), with the frame period taken from the log's keyframe stamps.
    const double period_s = framePeriod(log);
    const double one_step_us = std::abs(s.beta) * 1e6 * gain_;
    const double d_us = (period_s > 0 && log.height > 1 && readout_fraction_ > 0) ? 1e6 * readout_fraction_ * period_s / log.height : one_step_us;
    // Line delays are written with 3 significant digits.
    std::ostringstream ld;
    ld.precision(3);
    ld << d_us;
    r.config_line = "--set shutter.plugin=shutter.rolling --set shutter.params.line_delay_us=" + ld.str();
    if (s.beta < 0) r.config_line += " --set shutter.params.readout=bottom_up";
    else r.config_line += " --set shutter.params.readout=top_down";
    std::ostringstream ex;
    ex.precision(3);
    ex << "residual follows row x pixel velocity (|z| = " << std::abs(s.z) << "), "
       << (s.beta < 0 ? "bottom-up" : "top-down") << " readout; suggested line delay " << d_us << " us per row ("
       << 100.0 * readout_fraction_ << " % of the frame period, "
       << d_us * 1e-3 * std::max(1, log.height) << " ms readout; the residuals give the direction, not the value)";
    r.explanation = ex.str();
    r.details = probe::toJson(s);
    r.details["line_delay_us_one_step"] = s.beta * 1e6;
    r.details["frame_period_s"] = period_s;
    r.details["readout_fraction"] = readout_fraction_;
    r.details["line_delay_us_suggested"] = d_us;
    r.details["curve"] = probe::toJson(s.curve, "-(gradient . pixel velocity) x (row - y0) [1e6 intensity rows / s]",
                                       "residual (brightness removed per pair)");
    probe::finish(r);
    return r;
  }

 private:
  double threshold_;
  double gain_;
  double clip_;
  double readout_fraction_;
};

ParamTable table() {
  return {paramDouble("threshold", 4.0, 0.0, 1e6, "",
                      "|z| of the line-delay score test above which the effect is named (README: false-alarm rate)"),
          paramDouble("estimate_gain", 1.0, 0.0, 100.0, "",
                      "factor from the one-step line-delay estimate to the suggested line_delay_us"),
          paramDouble("clip", 3.0, 0.0, 1e6, "",
                      "the regressor is clipped at this many times its median magnitude (0: not clipped)"),
          paramDouble("readout_fraction", 0.6, 0.0, 1.0, "",
                      "suggested readout time as a fraction of the frame period (0: the one-step estimate instead)")};
}

void registerAll(PluginRegistrar& r) {
  r.add<DiagnosticProbe>({kName, PluginKind::Probe, "1.0.0",
                          "Rolling shutter: score test of the line delay (residual against row x pixel velocity)",
                          table(), ""},
                         [](const Params& p) { return std::make_unique<RollingShutterProbe>(p); });
}

}  // namespace
}  // namespace rsvio

RSVIO_PLUGIN_ENTRY(rsvio::registerAll)
