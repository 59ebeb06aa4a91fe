// A radial vignette fitted to photometric residuals: what probe.vignetting suggests from a finished
// run's diagnostics log, and what photometric.vignette in mode "estimate" refines online from the
// observations that leave the window.
//
// Model: V(rho) = 1 + k1 rho^2 + k2 rho^4 + k3 rho^6 multiplies the irradiance, rho the distance from
// the principal point normalised so that rho is in [0, 1] over the image. An observation of host
// intensity I seen at host radius rho_h and target radius rho_t has the residual
//   r = I (V(rho_t) / V(rho_h) - 1)
// once each (target, host) pair's gain and offset are removed (projected off [1, I] with the weights:
// what photometric.affine absorbs). fitVignette minimises the pairs' projected residuals over the
// first n_params of (k1, k2, k3) by Gauss-Newton with Levenberg-Marquardt damping; weights are each
// row's robust weight (an outlier's 0 counts as 1: the outlier threshold cuts off the largest
// vignetting residuals, a corner against the centre) times a Huber weight at 1.345 sigma of the
// residuals at k = 0.
#pragma once
#include <Eigen/Core>
#include <vector>

#include "rsvio/io/diagnostics_log.h"

namespace rsvio {

struct VignetteFit {
  Eigen::Vector3d k = Eigen::Vector3d::Zero();
  int params = 0;          // the parameters fitted (1 or 3)
  int iterations = 0;
  size_t rows = 0;         // rows used (in pairs of at least min_pair rows)
  double cost_null = 0.0;  // robust energy of the projected residuals at k = 0
  double cost = 0.0;       // at the fit
};

// The weighted projection of v off the columns [1, I] (a pair's gain and offset on its host
// intensities I); only the mean when the intensities are all alike. probe.* share it (probe_common.h).
void projectOffGainOffset(const std::vector<double>& w, const std::vector<double>& I, std::vector<double>& v);

// The model residual of one observation, m = I (V(rho_t) / V(rho_h) - 1), and (when J) its derivative
// with respect to (k1, k2, k3): dm/dk_j = I (rho_t^2j V(rho_h) - V(rho_t) rho_h^2j) / V(rho_h)^2.
double vignetteResidual(const Eigen::Vector3d& k, double intensity, double rho_t, double rho_h, Eigen::Vector3d* J);

// V(rho) of the polynomial k.
double vignetteValue(const Eigen::Vector3d& k, double rho);

// V plausible on [0, 1]: above 0.05 and below 1.5 everywhere.
bool plausibleVignette(const Eigen::Vector3d& k);

// The polynomial nearest to V_a(rho) V_b(rho) (least squares on 101 radii in [0, 1]).
Eigen::Vector3d vignetteProduct(const Eigen::Vector3d& a, const Eigen::Vector3d& b);

// rho_scale multiplies each row's radius and host_radius (rows normalise by the half diagonal; a
// model with another normaliser passes the ratio). Rows without a finite host_radius are skipped.
VignetteFit fitVignette(const std::vector<ObservationRow>& rows, int n_params, double rho_scale = 1.0,
                        size_t min_pair = 12);

// fitVignette with three parameters, falling back to k1 alone when the three leave V implausible, and
// to zero when that is implausible too.
VignetteFit fitVignettePlausible(const std::vector<ObservationRow>& rows, double rho_scale = 1.0);

}  // namespace rsvio
