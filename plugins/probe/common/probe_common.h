// Shared statistics of the probe.* plugins (header-only; this folder has no CMakeLists.txt, so the
// build does not take it for a plugin). Every probe works on the run's diagnostics log alone
// (rsvio/io/diagnostics_log.h) and its effective config; none reads truth.json or ground truth.
//
// Observations are grouped into clusters, one per (target frame, host keyframe) pair: within a pair the
// affine brightness (a, b) acts as one gain and offset, so "what the run already explains" is removed
// per pair by projecting the residual and the regressor off the nuisance columns [1, I] (I the host
// intensity) with the robust weights. What is left is tested with a score/Wald test:
//   beta = sum_c s_c / sum_c i_c,   s_c = sum_{i in c} w x_perp r_perp,   i_c = sum_{i in c} w x_perp^2
//   z    = beta / se,               se^2 = sum_c (s_c - i_c beta)^2 / (sum_c i_c)^2
// (cluster-robust "sandwich" standard error: observations seen in one target keyframe share its pose
// and brightness errors, so they are not independent; target keyframes are treated as independent). Under "no such
// effect" z is approximately N(0, 1). beta is one Gauss-Newton step of the effect's parameter from its
// null value, i.e. the score normalised by its information.
#pragma once
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "rsvio/interfaces/diagnostic_probe.h"
#include "rsvio/io/diagnostics_log.h"
#include "rsvio/photometric/vignette_fit.h"

namespace rsvio::probe {

// True when any slot of the config (shutter, photometric members, ...) names `plugin`.
inline bool usesPlugin(const nlohmann::json& j, const std::string& plugin) {
  if (j.is_object()) {
    for (auto it = j.begin(); it != j.end(); ++it) {
      if (it.key() == "plugin" && it.value().is_string() && it.value().get<std::string>() == plugin) return true;
      if (usesPlugin(it.value(), plugin)) return true;
    }
  } else if (j.is_array()) {
    for (const auto& v : j)
      if (usesPlugin(v, plugin)) return true;
  }
  return false;
}

inline bool usable(const ObservationRow& o) {
  return std::isfinite(o.residual) && std::isfinite(o.weight) && o.weight > 0 && std::isfinite(o.intensity) &&
         std::isfinite(o.row) && std::isfinite(o.radius) && std::isfinite(o.grad_u) && std::isfinite(o.grad_v) &&
         std::isfinite(o.vel_u) && std::isfinite(o.vel_v);
}


// Indices of usable observations grouped by (frame, host), clusters in frame order.
inline std::vector<std::vector<size_t>> clusters(const DiagnosticsLog& log, size_t min_size) {
  std::map<int64_t, std::vector<size_t>> by;
  for (size_t i = 0; i < log.observations.size(); ++i)
    if (usable(log.observations[i])) by[pairKey(log.observations[i])].push_back(i);
  std::vector<std::vector<size_t>> out;
  for (auto& [k, v] : by)
    if (v.size() >= min_size) out.push_back(std::move(v));
  return out;
}

// How much data the log holds (diagnose prints it; a failed run has less).
inline nlohmann::json dataSummary(const DiagnosticsLog& log) {
  size_t usable_n = 0;
  int fmin = 1 << 30, fmax = -1;
  int64_t tmin = INT64_MAX, tmax = INT64_MIN;
  std::map<int, int> frames;
  for (const auto& o : log.observations) {
    if (!usable(o)) continue;
    ++usable_n;
    frames[o.frame] = 1;
    fmin = std::min(fmin, o.frame);
    fmax = std::max(fmax, o.frame);
    tmin = std::min(tmin, o.t_ns);
    tmax = std::max(tmax, o.t_ns);
  }
  nlohmann::json j;
  j["observations"] = log.observations.size();
  j["usable_observations"] = usable_n;
  j["keyframes"] = frames.size();
  j["pairs"] = clusters(log, 1).size();
  j["first_frame"] = fmax >= 0 ? fmin : -1;
  j["last_frame"] = fmax;
  j["span_s"] = fmax >= 0 ? 1e-9 * static_cast<double>(tmax - tmin) : 0.0;
  return j;
}

// Weighted projection of the columns of v off the nuisance columns [1, I] (k = 0, 1 or 2 of them).
struct Nuisance {
  int k = 2;  // 0: none, 1: [1], 2: [1, I]
};

inline void projectOff(const std::vector<double>& w, const std::vector<double>& I, int k, std::vector<double>& v) {
  if (k == 0 || v.empty()) return;
  if (k == 2) {
    projectOffGainOffset(w, I, v);  // rsvio/photometric/vignette_fit.h
    return;
  }
  double s0 = 0, t0 = 0;
  for (size_t i = 0; i < v.size(); ++i) {
    s0 += w[i];
    t0 += w[i] * v[i];
  }
  if (!(s0 > 0)) return;
  const double m = t0 / s0;
  for (auto& x : v) x -= m;
}

// Binned curve of the evidence: mean projected residual (and mean fitted part) per bin of the
// explaining variable (quantile bins, so each holds about the same number of observations).
struct Binned {
  std::vector<double> x, y, fit, count;
};

struct PooledResult {
  double beta = 0;         // one Gauss-Newton step of the parameter from 0 (score / information)
  double se = 0;           // cluster-robust standard error of beta
  double z = 0;            // beta / se
  double z_naive = 0;      // score / sqrt(sigma^2 information), as if observations were independent
  double information = 0;  // sum w x_perp^2
  double sigma = 0;        // weighted RMS of the projected residual
  double explained = 0;    // fraction of the projected residual energy beta explains
  size_t n = 0;
  size_t clusters = 0;
  size_t groups = 0;       // target keyframes (independent units of the sandwich)
  Binned curve;            // residual against the explaining variable
};

// x_of(o): the regressor (the residual this effect's parameter would explain per unit parameter);
// e_of(o): the explaining variable shown in the figure (row * velocity, radius, intensity, ...).
inline PooledResult pooledScore(const DiagnosticsLog& log, const std::function<double(const ObservationRow&)>& x_of,
                                const std::function<double(const ObservationRow&)>& e_of, int nuisance_k,
                                size_t min_cluster = 12, int bins = 16) {
  PooledResult res;
  const auto cl = clusters(log, min_cluster);
  std::vector<double> sc, ic;
  std::vector<int32_t> cframe;  // target frame of each pair: the sandwich groups pairs by target
  std::vector<double> all_e, all_r, all_x;
  double S = 0, I = 0, E = 0;
  size_t dof_used = 0;
  for (const auto& idx : cl) {
    std::vector<double> w, in, x, r;
    for (size_t i : idx) {
      const ObservationRow& o = log.observations[i];
      const double xv = x_of(o);
      if (!std::isfinite(xv)) continue;
      w.push_back(o.weight);
      in.push_back(o.intensity);
      x.push_back(xv);
      r.push_back(o.residual);
      all_e.push_back(e_of(o));
    }
    if (x.size() < min_cluster) {
      all_e.resize(all_e.size() - x.size());
      continue;
    }
    projectOff(w, in, nuisance_k, x);
    projectOff(w, in, nuisance_k, r);
    double s = 0, ii = 0, e = 0;
    for (size_t i = 0; i < x.size(); ++i) {
      s += w[i] * x[i] * r[i];
      ii += w[i] * x[i] * x[i];
      e += w[i] * r[i] * r[i];
      all_r.push_back(r[i]);
      all_x.push_back(x[i]);
    }
    sc.push_back(s);
    ic.push_back(ii);
    cframe.push_back(log.observations[idx.front()].frame);
    S += s;
    I += ii;
    E += e;
    res.n += x.size();
    dof_used += static_cast<size_t>(nuisance_k);
  }
  res.clusters = sc.size();
  res.information = I;
  if (res.clusters < 2 || !(I > 0)) return res;
  res.beta = S / I;
  // Pairs sharing a target share its pose error: the sandwich sums their score terms before squaring.
  std::map<int32_t, double> per_target;
  for (size_t c = 0; c < sc.size(); ++c) per_target[cframe[c]] += sc[c] - ic[c] * res.beta;
  double V = 0;
  for (const auto& [f, u] : per_target) V += u * u;
  res.groups = per_target.size();
  // Small-sample correction of the sandwich (G / (G - 1)).
  if (res.groups > 1) V *= static_cast<double>(res.groups) / static_cast<double>(res.groups - 1);
  res.se = std::sqrt(V) / I;
  res.z = res.se > 0 ? res.beta / res.se : 0.0;
  const double dof = std::max<double>(1.0, static_cast<double>(res.n) - static_cast<double>(dof_used));
  const double sigma2 = E / dof;
  res.sigma = std::sqrt(std::max(0.0, sigma2));
  res.z_naive = sigma2 > 0 ? S / std::sqrt(sigma2 * I) : 0.0;
  res.explained = E > 0 ? S * S / I / E : 0.0;

  // Quantile bins of the explaining variable.
  std::vector<size_t> order(all_e.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return all_e[a] < all_e[b]; });
  const size_t nb = std::min<size_t>(static_cast<size_t>(bins), std::max<size_t>(1, order.size() / 20));
  for (size_t b = 0; b < nb && !order.empty(); ++b) {
    const size_t lo = b * order.size() / nb, hi = (b + 1) * order.size() / nb;
    if (hi <= lo) continue;
    double se = 0, sr = 0, sf = 0;
    for (size_t k = lo; k < hi; ++k) {
      se += all_e[order[k]];
      sr += all_r[order[k]];
      sf += res.beta * all_x[order[k]];
    }
    const double m = static_cast<double>(hi - lo);
    res.curve.x.push_back(se / m);
    res.curve.y.push_back(sr / m);
    res.curve.fit.push_back(sf / m);
    res.curve.count.push_back(m);
  }
  return res;
}

inline nlohmann::json toJson(const Binned& b, const std::string& x_label, const std::string& y_label) {
  return {{"x", b.x}, {"y", b.y}, {"fit", b.fit}, {"count", b.count}, {"x_label", x_label}, {"y_label", y_label}};
}

inline nlohmann::json toJson(const PooledResult& p) {
  return {{"beta", p.beta}, {"se", p.se}, {"z", p.z}, {"z_naive", p.z_naive}, {"information", p.information},
          {"sigma", p.sigma}, {"explained_fraction", p.explained}, {"observations", p.n}, {"pairs", p.clusters}, {"target_keyframes", p.groups}};
}

// The common tail of evaluate(): score, and the verdict fields.
inline void finish(ProbeResult& r) {
  r.score = r.threshold > 0 ? r.statistic / r.threshold : 0.0;
  if (!std::isfinite(r.score)) r.score = 0.0;
}

inline ProbeResult notApplicable(const std::string& effect, const std::string& plugin, const std::string& why) {
  ProbeResult r;
  r.effect = effect;
  r.plugin = plugin;
  r.applicable = false;
  r.explanation = why;
  return r;
}

inline ProbeResult tooLittleData(const std::string& effect, const std::string& plugin, size_t n, double threshold) {
  ProbeResult r;
  r.effect = effect;
  r.plugin = plugin;
  r.threshold = threshold;
  r.statistic = 0;
  r.score = 0;
  r.explanation = "too little data (" + std::to_string(n) + " usable observations in usable pairs)";
  return r;
}

}  // namespace rsvio::probe
