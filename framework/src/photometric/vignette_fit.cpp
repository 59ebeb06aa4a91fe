// The vignette fit of photometric residuals (contract in rsvio/photometric/vignette_fit.h).
#include "rsvio/photometric/vignette_fit.h"

#include <Eigen/Dense>
#include <cmath>
#include <cstdint>
#include <map>

namespace rsvio {
namespace {

struct Pair {
  std::vector<double> w, I, rt, rh, r;
};

}  // namespace

void projectOffGainOffset(const std::vector<double>& w, const std::vector<double>& I, std::vector<double>& v) {
  double s0 = 0, s1 = 0, s2 = 0, t0 = 0, t1 = 0;
  for (size_t i = 0; i < v.size(); ++i) {
    s0 += w[i];
    s1 += w[i] * I[i];
    s2 += w[i] * I[i] * I[i];
    t0 += w[i] * v[i];
    t1 += w[i] * I[i] * v[i];
  }
  if (!(s0 > 0)) return;
  const double det = s0 * s2 - s1 * s1;
  if (!(det > 1e-9 * s0 * s2)) {  // intensities all alike: only the mean can be removed
    const double m = t0 / s0;
    for (auto& x : v) x -= m;
    return;
  }
  const double c0 = (s2 * t0 - s1 * t1) / det;
  const double c1 = (s0 * t1 - s1 * t0) / det;
  for (size_t i = 0; i < v.size(); ++i) v[i] -= c0 + c1 * I[i];
}

double vignetteResidual(const Eigen::Vector3d& k, double intensity, double rho_t, double rho_h, Eigen::Vector3d* J) {
  const double vt = vignetteValue(k, rho_t), vh = vignetteValue(k, rho_h);
  if (J) {
    double qt = 1.0, qh = 1.0;
    for (int j = 0; j < 3; ++j) {
      qt *= rho_t * rho_t;
      qh *= rho_h * rho_h;
      (*J)[j] = intensity * (qt * vh - vt * qh) / (vh * vh);
    }
  }
  return intensity * (vt / vh - 1.0);
}

double vignetteValue(const Eigen::Vector3d& k, double rho) {
  const double q = rho * rho;
  return 1.0 + q * (k[0] + q * (k[1] + q * k[2]));
}

bool plausibleVignette(const Eigen::Vector3d& k) {
  if (!k.allFinite()) return false;
  for (int i = 0; i <= 20; ++i) {
    const double v = vignetteValue(k, i / 20.0);
    if (!(v > 0.05 && v < 1.5)) return false;
  }
  return true;
}

Eigen::Vector3d vignetteProduct(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Eigen::Vector3d y = Eigen::Vector3d::Zero();
  for (int i = 0; i <= 100; ++i) {
    const double rho = i / 100.0, q = rho * rho;
    const Eigen::Vector3d x(q, q * q, q * q * q);
    A += x * x.transpose();
    y += x * (vignetteValue(a, rho) * vignetteValue(b, rho) - 1.0);
  }
  return A.ldlt().solve(y);
}

VignetteFit fitVignette(const std::vector<ObservationRow>& rows, int n_params, double rho_scale, size_t min_pair) {
  VignetteFit fit;
  fit.params = n_params;
  std::map<int64_t, Pair> by_pair;
  for (const ObservationRow& o : rows) {
    if (!(std::isfinite(o.residual) && std::isfinite(o.intensity) && std::isfinite(o.radius) &&
          std::isfinite(o.host_radius) && std::isfinite(o.weight) && o.weight >= 0.f))
      continue;
    Pair& p = by_pair[pairKey(o)];
    p.w.push_back(o.weight > 0.f ? o.weight : 1.0);
    p.I.push_back(o.intensity);
    p.rt.push_back(rho_scale * o.radius);
    p.rh.push_back(rho_scale * o.host_radius);
    p.r.push_back(o.residual);
  }
  std::vector<Pair> pairs;
  for (auto& [key, p] : by_pair)
    if (p.w.size() >= min_pair) {
      fit.rows += p.w.size();
      pairs.push_back(std::move(p));
    }
  if (pairs.empty() || n_params < 1 || n_params > 3) return fit;
  const int n = n_params;
  // The robust energy of the projected residuals at k, with (when H) the normal equations.
  const auto evaluate = [&](const Eigen::Vector3d& k, double huber, Eigen::MatrixXd* H, Eigen::VectorXd* g) {
    if (H) {
      H->setZero(n, n);
      g->setZero(n);
    }
    double cost = 0.0;
    std::vector<double> e;
    std::vector<std::vector<double>> J(static_cast<size_t>(n));
    for (const Pair& p : pairs) {
      const size_t m = p.w.size();
      e.resize(m);
      for (auto& c : J) c.resize(m);
      Eigen::Vector3d Ji;
      for (size_t i = 0; i < m; ++i) {
        e[i] = p.r[i] - vignetteResidual(k, p.I[i], p.rt[i], p.rh[i], &Ji);
        for (int j = 0; j < n; ++j) J[static_cast<size_t>(j)][i] = Ji[j];
      }
      projectOffGainOffset(p.w, p.I, e);
      for (auto& c : J) projectOffGainOffset(p.w, p.I, c);
      for (size_t i = 0; i < m; ++i) {
        const double a = std::abs(e[i]);
        const bool clipped = huber > 0 && a > huber;
        cost += p.w[i] * (clipped ? huber * (2.0 * a - huber) : a * a);
        if (!H) continue;
        const double w = p.w[i] * (clipped ? huber / a : 1.0);
        for (int r = 0; r < n; ++r) {
          (*g)[r] += w * J[static_cast<size_t>(r)][i] * e[i];
          for (int c = 0; c < n; ++c) (*H)(r, c) += w * J[static_cast<size_t>(r)][i] * J[static_cast<size_t>(c)][i];
        }
      }
    }
    return cost;
  };
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

VignetteFit fitVignettePlausible(const std::vector<ObservationRow>& rows, double rho_scale) {
  VignetteFit fit = fitVignette(rows, 3, rho_scale);
  if (!plausibleVignette(fit.k)) fit = fitVignette(rows, 1, rho_scale);
  if (!plausibleVignette(fit.k)) fit.k.setZero();
  return fit;
}

}  // namespace rsvio
