// probe.vignetting: does the run miss a radial fall-off of the irradiance (vignetting)?
//
// Physics: with vignetting V(rho) = 1 + k1 rho^2 + k2 rho^4 + k3 rho^6 (rho the distance from the
// principal point over the half diagonal) the same scene point is brighter near the centre: the
// residual of a point of host intensity I seen at host radius rho_h and target radius rho_t is
//   r = I (V(rho_t) / V(rho_h) - 1) ~ k1 I (rho_t^2 - rho_h^2).
// The statistic: after removing the pair's gain and offset ([1, I], what photometric.affine absorbs)
// the regressor x = I rho_t^2 carries k1; the cluster-robust score test of k1 = 0, |z|
// (plugins/probe/common/probe_common.h). Its one-step k1 is biased towards 0 (host and target radii of
// a point are correlated), so it is reported but not suggested.
// The estimate suggested: (k1, k2, k3) fitted to the residuals with the full ratio V(rho_t) / V(rho_h)
// (the log's host_radius), each pair projected off [1, I], Gauss-Newton with Levenberg-Marquardt
// damping and Huber weights on top of the run's robust weights (fitVignette below).
#include <Eigen/Dense>
#include <cmath>
#include <map>
#include <memory>
#include <sstream>

#include "../common/probe_common.h"
#include "rsvio/plugin/plugin_api.h"

namespace rsvio {
namespace {

const char* kName = "probe.vignetting";

double vignette(const Eigen::Vector3d& k, double rho) {
  const double q = rho * rho;
  return 1.0 + q * (k[0] + q * (k[1] + q * k[2]));
}

struct VignetteFit {
  Eigen::Vector3d k = Eigen::Vector3d::Zero();
  int params = 0;          // 3, or 1 when the three-term fit left the plausible range
  int iterations = 0;
  double cost_null = 0.0;  // weighted projected residual energy at k = 0
  double cost = 0.0;       // at the fit
};

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

// The product V_a(rho) V_b(rho) as one polynomial 1 + k1 rho^2 + k2 rho^4 + k3 rho^6: least squares on
// 101 radii in [0, 1] (the product has terms up to rho^12).
Eigen::Vector3d product(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Eigen::Vector3d y = Eigen::Vector3d::Zero();
  for (int i = 0; i <= 100; ++i) {
    const double rho = i / 100.0, q = rho * rho;
    const Eigen::Vector3d x(q, q * q, q * q * q);
    A += x * x.transpose();
    y += x * (vignette(a, rho) * vignette(b, rho) - 1.0);
  }
  return A.ldlt().solve(y);
}

// V plausible on [0, 1]: positive with a margin and not brighter than 1.5 x the centre.
bool plausible(const Eigen::Vector3d& k) {
  for (int i = 0; i <= 20; ++i) {
    const double v = vignette(k, i / 20.0);
    if (!(v > 0.05 && v < 1.5)) return false;
  }
  return true;
}

// Least squares over the pairs' projected residuals e = P (r - m(k)), m_i(k) = I_i (V(rho_t)/V(rho_h) - 1),
// with the first n_params of (k1, k2, k3) free. Weights: the log's robust weight times a Huber weight
// (threshold 1.345 sigma of the current projected residuals).
VignetteFit fitVignette(const DiagnosticsLog& log, int n_params) {
  struct Pair {
    std::vector<double> w, I, rt, rh, r;
  };
  // Pairs as probe::clusters, but with the outliers (weight 0 in the log) at full weight: the outlier
  // threshold cuts off the largest vignetting residuals (a corner against the centre), and without
  // them the fit is biased towards no vignetting.
  std::map<int64_t, Pair> by_pair;
  for (const ObservationRow& o : log.observations) {
    if (!(std::isfinite(o.residual) && std::isfinite(o.intensity) && std::isfinite(o.radius) &&
          std::isfinite(o.host_radius) && std::isfinite(o.weight) && o.weight >= 0.f))
      continue;
    Pair& p = by_pair[probe::pairKey(o)];
    p.w.push_back(o.weight > 0.f ? o.weight : 1.0);
    p.I.push_back(o.intensity);
    p.rt.push_back(o.radius);
    p.rh.push_back(o.host_radius);
    p.r.push_back(o.residual);
  }
  std::vector<Pair> pairs;
  for (auto& [key, p] : by_pair)
    if (p.w.size() >= 12) pairs.push_back(std::move(p));
  VignetteFit fit;
  fit.params = n_params;
  if (pairs.empty()) return fit;
  const int n = n_params;
  // Projected residuals and Jacobian columns at k; returns the Huber-weighted cost.
  const auto evaluate = [&](const Eigen::Vector3d& k, double huber, Eigen::MatrixXd* H, Eigen::VectorXd* g) {
    if (H) H->setZero(n, n);
    if (g) g->setZero(n);
    double cost = 0.0;
    for (const Pair& p : pairs) {
      const size_t m = p.w.size();
      std::vector<double> e(m);
      std::vector<std::vector<double>> J(static_cast<size_t>(n), std::vector<double>(m));
      for (size_t i = 0; i < m; ++i) {
        const double vt = vignette(k, p.rt[i]), vh = vignette(k, p.rh[i]);
        e[i] = p.r[i] - p.I[i] * (vt / vh - 1.0);
        double pt = 1.0, ph = 1.0;
        for (int j = 0; j < n; ++j) {
          pt *= p.rt[i] * p.rt[i];
          ph *= p.rh[i] * p.rh[i];
          J[static_cast<size_t>(j)][i] = p.I[i] * (pt * vh - vt * ph) / (vh * vh);  // d m_i / d k_j
        }
      }
      probe::projectOff(p.w, p.I, 2, e);
      for (auto& c : J) probe::projectOff(p.w, p.I, 2, c);
      for (size_t i = 0; i < m; ++i) {
        const double a = std::abs(e[i]);
        const double hw = (huber > 0 && a > huber) ? huber / a : 1.0;
        const double w = p.w[i] * hw;
        cost += p.w[i] * ((huber > 0 && a > huber) ? huber * (2.0 * a - huber) : a * a);
        if (!H) continue;
        for (int r = 0; r < n; ++r) {
          (*g)[r] += w * J[static_cast<size_t>(r)][i] * e[i];
          for (int c = 0; c < n; ++c) (*H)(r, c) += w * J[static_cast<size_t>(r)][i] * J[static_cast<size_t>(c)][i];
        }
      }
    }
    return cost;
  };
  // The Huber threshold from the residuals at k = 0 (weighted RMS).
  double sw = 0.0;
  for (const Pair& p : pairs)
    for (double w : p.w) sw += w;
  const double sigma = std::sqrt(evaluate(Eigen::Vector3d::Zero(), 0.0, nullptr, nullptr) / std::max(sw, 1e-12));
  const double huber = 1.345 * sigma;
  Eigen::Vector3d k = Eigen::Vector3d::Zero();
  Eigen::MatrixXd H;
  Eigen::VectorXd g;
  double cost = evaluate(k, huber, &H, &g);
  fit.cost_null = cost;
  double lambda = 1e-4;
  for (int it = 0; it < 30; ++it) {
    Eigen::MatrixXd A = H;
    for (int j = 0; j < n; ++j) A(j, j) *= 1.0 + lambda;
    const Eigen::VectorXd dk = A.ldlt().solve(g);
    if (!dk.allFinite()) break;
    Eigen::Vector3d kn = k;
    kn.head(n) += dk;
    Eigen::MatrixXd Hn;
    Eigen::VectorXd gn;
    const double cn = evaluate(kn, huber, &Hn, &gn);
    fit.iterations = it + 1;
    if (cn < cost) {
      const double rel = (cost - cn) / std::max(cost, 1e-300);
      k = kn;
      cost = cn;
      H = Hn;
      g = gn;
      lambda = std::max(lambda * 0.3, 1e-8);
      if (rel < 1e-9) break;
    } else {
      lambda *= 10.0;
      if (lambda > 1e6) break;
    }
  }
  fit.k = k;
  fit.cost = cost;
  return fit;
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
      return static_cast<double>(o.intensity) * o.radius * o.radius;
    };
    const auto e_of = [](const ObservationRow& o) { return static_cast<double>(o.radius); };
    const probe::PooledResult s = probe::pooledScore(log, x_of, e_of, 2);
    if (s.clusters < 3) return probe::tooLittleData(effect(), "photometric.vignette", s.n, 1.0);
    ProbeResult r;
    r.effect = effect();
    r.plugin = "photometric.vignette";
    // A vignette darkens the border: only a negative k1 is vignetting (a positive one is something else).
    r.threshold = 1.0;
    VignetteFit fit = fitVignette(log, 3);
    if (!plausible(fit.k)) fit = fitVignette(log, 1);
    if (!plausible(fit.k) || fit.k[0] > 0.0) fit.k.setZero();  // no fall-off fitted: suggest nothing to divide by
    const Eigen::Vector3d k = refine ? product(k_run, fit.k) : fit.k;
    // Both conditions, each against its own threshold: the score test, -z / threshold, and the fitted
    // fall-off at the corner (what the run's images still lack), 1 - V(1) / min_falloff; named above 1.
    const double z_part = std::max(0.0, -s.z) / threshold_;
    const double falloff = 1.0 - vignette(fit.k, 1.0);
    r.statistic = std::min(z_part, min_falloff_ > 0 ? std::max(0.0, falloff) / min_falloff_ : INFINITY);
    std::ostringstream line;
    line.precision(3);
    line << "--set photometric.vignette.plugin=photometric.vignette --set photometric.vignette.params.mode=fixed"
         << " --set photometric.vignette.params.initial=[" << k[0] << "," << k[1] << "," << k[2] << "]";
    r.config_line = line.str();
    std::ostringstream ex;
    ex.precision(3);
    ex << "residual falls with image radius (z = " << s.z << "), fitted V(rho) = 1 + " << k[0] << " rho^2 + " << k[1]
       << " rho^4 + " << k[2] << " rho^6, corner at ~" << 100.0 * vignette(k, 1.0) << " % of the centre";
    if (refine)
      ex << " (the run's fixed polynomial, corner at " << 100.0 * vignette(k_run, 1.0)
         << " %, left a corner at " << 100.0 * vignette(fit.k, 1.0) << " %)";
    r.explanation = ex.str();
    r.details = probe::toJson(s);
    r.details["k1_one_step"] = s.beta;
    r.details["k_fitted"] = {k[0], k[1], k[2]};
    r.details["fit_params"] = fit.params;
    r.details["fit_iterations"] = fit.iterations;
    r.details["fit_cost_null"] = fit.cost_null;
    r.details["fit_cost"] = fit.cost;
    r.details["corner_ratio"] = vignette(k, 1.0);
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
