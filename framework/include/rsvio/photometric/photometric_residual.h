// The photometric residual of one point observation: the kernel shared by the frame tracker and the
// back end's bundle adjustment (paper section IV-A, eq. 8; DSO, Engel et al. 2018, eq. 4).
//
// Contract
// - A point p is hosted in frame i at an integer level-0 pixel; its pattern (residual_pattern.h) has
//   host intensities I_i[p + o_k]. Seen in target j at pixel p' (the RS projection of the point, raw
//   target image), pattern pixel k sits at p' + W o_k, where W = d p' / d p (host pixel -> target
//   pixel at fixed inverse depth) is evaluated at the current estimate and held constant inside one
//   linearisation (DSO evaluates every pattern pixel with the centre's geometric Jacobian; we do the
//   same and also place the pattern with the centre's warp, so the residual model and its Jacobian agree
//   exactly). W = I is the tracker's choice.
// - Residual (affine brightness, DSO eq. 4 without exposure times; exposure_ratio t_j / t_i when known):
//     r_k = (I_j[p' + W o_k] - b_j) - exposure_ratio * exp(a_j - a_i) * (I_i[p + o_k] - b_i)
//         = I_j[...] - (alpha * I_i[...] + beta),  alpha = exposure_ratio * exp(a_j - a_i), beta = b_j - alpha b_i.
//   Intensities in the working domain (0..255 scale), bilinear interpolation with interpolated
//   central-difference gradients in the target.
// - Weights (DSO): gradient weight w_g = 0.5 (w(g_host) + w(g_target)), w(g) = sqrt(c^2 / (c^2 + |g|^2)),
//   so the squared weight of a residual is ~ c^2 / (c^2 + |grad|^2); Huber with threshold huber_th:
//     energy  E = sum_k w_g,k^2 * rho(r_k),  rho(r) = r^2 (|r| <= k), 2 k |r| - k^2 otherwise;
//     IRLS weight of r_k in the normal equations  w_k = w_g,k^2 * min(1, k / |r_k|).
//   An observation whose energy exceeds outlier_th^2 * kPatternSize is an outlier (DSO's energy test).
// - Jacobians: d r_k / d p' = (gx_k, gy_k) in intensity per level-0 pixel (the level gradient divided by
//   the level scale); any state enters through d p' / d state (2 x n, from the projection), so
//   d r / d state = G * d p' / d state with G the 8 x 2 matrix of gradients (see chainGeometry()).
//   Affine: d r_k / d a_j = -alpha (I_i - b_i), d r_k / d a_i = +alpha (I_i - b_i),
//           d r_k / d b_j = -1, d r_k / d b_i = +alpha.
// - Evaluation is batch-friendly: PatternHost is precomputed once per point; evaluatePattern() is an
//   inline template over the target sampler (ImageLevel in production, an analytic image in tests),
//   with no allocation and no virtual call.
#pragma once
#include <Eigen/Core>
#include <cmath>

#include "rsvio/photometric/image_pyramid.h"
#include "rsvio/photometric/residual_pattern.h"
#include "rsvio/plugin/plugin.h"

namespace rsvio {

struct ResidualOptions {
  double huber_th = 9.0;        // intensity units (DSO setting_huberTH)
  double grad_weight_c = 50.0;  // intensity per pixel (DSO sqrt(setting_outlierTHSumComponent))
  double outlier_th = 12.0;     // intensity units per pattern pixel (DSO setting_outlierTH = 12^2)

  double outlierEnergy() const { return outlier_th * outlier_th * kPatternSize; }
  static ParamTable paramTable();  // keys residual_* (see frontend_options.h)
  static ResidualOptions fromParams(const Params& p);
};

// Per-frame affine brightness (DSO's a, b; paper section IV-A).
struct AffineBrightness {
  double a = 0.0;
  double b = 0.0;
};

// Host -> target brightness transfer: predicted target intensity = alpha * I_host + beta.
struct AffineTransfer {
  double alpha = 1.0;
  double beta = 0.0;
};

inline AffineTransfer affineTransfer(const AffineBrightness& host, const AffineBrightness& target,
                                     double exposure_ratio = 1.0) {
  AffineTransfer t;
  t.alpha = exposure_ratio * std::exp(target.a - host.a);
  t.beta = target.b - t.alpha * host.b;
  return t;
}

inline float huberWeight(float r, float k) {
  const float a = std::abs(r);
  return a <= k ? 1.f : k / a;
}
inline float huberEnergy(float r, float k) {
  const float a = std::abs(r);
  return a <= k ? r * r : 2.f * k * a - k * k;
}
// sqrt(c^2 / (c^2 + |g|^2)) (DSO's per-pixel weight; its square weighs the residual).
inline float gradientWeight(float grad2, float c2) { return std::sqrt(c2 / (c2 + grad2)); }

// Host side of a point's pattern: intensities and host gradient weights, computed once.
struct PatternHost {
  float color[kPatternSize];
  float weight[kPatternSize];
};

// Samples the pattern around (u, v) in level coordinates of `host` (integer coordinates on level 0:
// exact pixel values). Returns false if any pattern pixel is outside the image (margin 1).
bool makePatternHost(const ImageLevel& host, float u, float v, const ResidualOptions& opt, PatternHost* out);

// Float copies of the options for the inner loops.
struct ResidualKernel {
  float huber = 9.f;
  float c2 = 2500.f;
  float outlier_energy = 1152.f;
  explicit ResidualKernel(const ResidualOptions& o)
      : huber(static_cast<float>(o.huber_th)),
        c2(static_cast<float>(o.grad_weight_c * o.grad_weight_c)),
        outlier_energy(static_cast<float>(o.outlierEnergy())) {}
  ResidualKernel() = default;
};

// Result of one pattern evaluation.
struct PatternResidual {
  float r[kPatternSize];       // residuals, intensity units
  float w[kPatternSize];       // IRLS weights w_g^2 * huberWeight
  float wg2[kPatternSize];     // squared gradient weights w_g^2
  float gx[kPatternSize];      // d r / d u' per level-0 pixel
  float gy[kPatternSize];      // d r / d v' per level-0 pixel
  float energy = 0.f;          // sum w_g^2 * rho(r)
  bool in_image = false;       // every pattern pixel could be sampled
  bool outlier = false;        // energy > outlier energy (only meaningful when in_image)
};

// Evaluates the pattern of one observation. (u, v): target position of the pattern centre in the
// sampler's own (level) coordinates; warp (row-major 2x2, level px per level px) places the offsets;
// inv_scale = 1 / level scale turns level gradients into per-level-0-pixel gradients.
// Sampler: bool inside(float u, float v, float margin) const; void sample(float u, float v, float* out4) const
// with out4 = (I, gx, gy, |g|^2) in level pixels.
template <class Sampler>
inline bool evaluatePattern(const Sampler& target, float u, float v, const float warp[4], float inv_scale,
                            const PatternHost& host, float alpha, float beta, const ResidualKernel& k,
                            PatternResidual& out) {
  float s[4];
  float energy = 0.f;
  for (int i = 0; i < kPatternSize; ++i) {
    const float du = warp[0] * kPattern[i][0] + warp[1] * kPattern[i][1];
    const float dv = warp[2] * kPattern[i][0] + warp[3] * kPattern[i][1];
    const float x = u + du, y = v + dv;
    if (!target.inside(x, y, 1.f)) {
      out.in_image = false;
      return false;
    }
    target.sample(x, y, s);
    const float r = s[0] - (alpha * host.color[i] + beta);
    const float wg = 0.5f * (host.weight[i] + gradientWeight(s[3], k.c2));
    const float wg2 = wg * wg;
    out.r[i] = r;
    out.w[i] = wg2 * huberWeight(r, k.huber);
    out.wg2[i] = wg2;
    out.gx[i] = s[1] * inv_scale;
    out.gy[i] = s[2] * inv_scale;
    energy += wg2 * huberEnergy(r, k.huber);
  }
  out.energy = energy;
  out.in_image = true;
  out.outlier = !(energy <= k.outlier_energy);
  return true;
}

// d r / d state = G (8x2) * d_p_d_state (2xN), G rows = (gx_k, gy_k).
template <int N>
inline Eigen::Matrix<double, kPatternSize, N> chainGeometry(const PatternResidual& res,
                                                            const Eigen::Matrix<double, 2, N>& d_p_d_state) {
  Eigen::Matrix<double, kPatternSize, 2> G;
  for (int i = 0; i < kPatternSize; ++i) G.row(i) << res.gx[i], res.gy[i];
  return G * d_p_d_state;
}

// Affine Jacobians of every pattern pixel: columns (a_host, b_host) and (a_target, b_target).
inline void affineJacobians(const PatternHost& host, const AffineBrightness& host_ab, double alpha,
                            Eigen::Matrix<double, kPatternSize, 2>* d_r_d_ab_host,
                            Eigen::Matrix<double, kPatternSize, 2>* d_r_d_ab_target) {
  for (int i = 0; i < kPatternSize; ++i) {
    const double c = alpha * (host.color[i] - host_ab.b);
    if (d_r_d_ab_host) d_r_d_ab_host->row(i) << c, alpha;
    if (d_r_d_ab_target) d_r_d_ab_target->row(i) << -c, -1.0;
  }
}

}  // namespace rsvio
