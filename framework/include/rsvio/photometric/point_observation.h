// Point observations for the bundle adjustment: a batch of points hosted in one keyframe, seen in one
// target frame, with residuals (photometric_residual.h) and the Jacobians w.r.t. every state they touch
// (paper sec. IV-A, eqs. 6-8; rolling-shutter geometry from geometry/rs_projection.h).
//
// Contract
// - A HostPoint is fixed in its host keyframe: level-0 host pixel uv_h (integer for selected points),
//   unit bearing b = unproject(uv_h) with d b / d uv_h, inverse depth rho = 1 / |X_h| along b, and its
//   PatternHost. In the world it sits at X_w = T_h(t_h)^-1 (b / rho), T_h(t) = exp(xi_h t) T_h^0,
//   t_h = t(v_h) (the host pixel's own row time).
// - Per observation: p' = the RS projection of X_w into the target (constraint solved); the pattern is
//   placed with the warp W = d p' / d uv_h at fixed rho (evaluated at the current estimate, held
//   constant in the linearisation; see photometric_residual.h), and sampled on the target's level 0.
// - Jacobians (8 rows, one per pattern pixel), all d r / d (state) with the project's conventions:
//     T_target, T_host: LEFT perturbation of the central poses T_c_w^0 (rsvio/lie/lie.h)
//     xi_target, xi_host: additive on the twists (per second)
//     idepth: additive on rho; (a, b) of host and target: additive
//     line_delay: additive, seconds (target and host row times; the pattern's own rows are not
//     differentiated, as the pattern shares the centre's geometry)
//   They are the exact derivatives of the residual model with W frozen (tests: numeric differences
//   through tests/support/numeric_jacobian.h with an analytic image).
// - Batch: evaluateObservations() makes one RS projection call per (host, target) pair and evaluates
//   every pattern inline; no virtual call per pixel, no allocation per residual (out is reused).
#pragma once
#include <Eigen/Core>
#include <vector>

#include "rsvio/geometry/rs_projection.h"
#include "rsvio/interfaces/camera.h"
#include "rsvio/photometric/photometric_residual.h"

namespace rsvio {

struct HostPoint {
  Vec2 uv = Vec2::Zero();          // host pixel, level 0
  Vec3 bearing = Vec3::UnitZ();    // unit bearing of uv
  Jac32 d_bearing_d_uv = Jac32::Zero();
  double idepth = 0.0;             // 1 / distance along the bearing
  PatternHost pattern;
};

// Builds host points for pixels of a keyframe (level-0 image of its pyramid). Pixels the camera cannot
// unproject or whose pattern leaves the image are dropped; `kept` (optional) receives the indices of
// the input pixels that were kept, in order.
std::vector<HostPoint> makeHostPoints(const CameraModel& camera, const ImageLevel& host_level0,
                                      const std::vector<Vec2>& uv, const std::vector<double>& idepth,
                                      const ResidualOptions& options, std::vector<int>* kept = nullptr);

// The result of one observation at the current estimate.
struct Observation {
  PatternResidual res;             // residuals, weights, gradients (per level-0 pixel), energy
  RsHostProjection proj;           // p' and its geometric Jacobians
  Eigen::Matrix2d warp = Eigen::Matrix2d::Identity();  // d p' / d uv_h at fixed rho
  double alpha = 1.0;              // exposure_ratio exp(a_t - a_h)
  bool valid = false;              // projected, in the image with the whole pattern
};

// Everything an observation's residuals depend on besides the images.
struct ObservationFrames {
  RsFrame host;
  RsFrame target;
  AffineBrightness host_affine;
  AffineBrightness target_affine;
  double exposure_ratio = 1.0;     // t_target / t_host when known
};

struct ObservationJacobians {
  Eigen::Matrix<double, kPatternSize, 6> d_r_d_T_target;
  Eigen::Matrix<double, kPatternSize, 6> d_r_d_xi_target;
  Eigen::Matrix<double, kPatternSize, 6> d_r_d_T_host;
  Eigen::Matrix<double, kPatternSize, 6> d_r_d_xi_host;
  Eigen::Matrix<double, kPatternSize, 1> d_r_d_idepth;
  Eigen::Matrix<double, kPatternSize, 2> d_r_d_ab_host;
  Eigen::Matrix<double, kPatternSize, 2> d_r_d_ab_target;
  Eigen::Matrix<double, kPatternSize, 1> d_r_d_line_delay;
};

// Evaluates all observations of `points` in the target. `warps` (optional, one per point) replaces the
// computed warps (numeric-difference tests freeze them this way). Sampler: see evaluatePattern().
template <class Sampler>
void evaluateObservations(const CameraModel& camera, const RowTiming& timing, const ObservationFrames& frames,
                          const Sampler& target_level0, const std::vector<HostPoint>& points,
                          const ResidualOptions& options, std::vector<Observation>& out,
                          const std::vector<Eigen::Matrix2d>* warps = nullptr);

// Full Jacobians of one valid observation (uses its stored gradients and geometric Jacobians).
ObservationJacobians observationJacobians(const Observation& obs, const HostPoint& point,
                                          const ObservationFrames& frames);

// ---- implementation of the template

namespace detail {
// Projection of every point (one batch call) and the warps; fills out[i].proj, warp, alpha.
void projectObservations(const CameraModel& camera, const RowTiming& timing, const ObservationFrames& frames,
                         const std::vector<HostPoint>& points, std::vector<Observation>& out);
}  // namespace detail

template <class Sampler>
void evaluateObservations(const CameraModel& camera, const RowTiming& timing, const ObservationFrames& frames,
                          const Sampler& target, const std::vector<HostPoint>& points, const ResidualOptions& options,
                          std::vector<Observation>& out, const std::vector<Eigen::Matrix2d>* warps) {
  detail::projectObservations(camera, timing, frames, points, out);
  const ResidualKernel kernel(options);
  const AffineTransfer tr = affineTransfer(frames.host_affine, frames.target_affine, frames.exposure_ratio);
  for (size_t i = 0; i < points.size(); ++i) {
    Observation& o = out[i];
    o.valid = false;
    if (!o.proj.valid) continue;
    if (warps) o.warp = (*warps)[i];
    const float w[4] = {static_cast<float>(o.warp(0, 0)), static_cast<float>(o.warp(0, 1)),
                        static_cast<float>(o.warp(1, 0)), static_cast<float>(o.warp(1, 1))};
    o.valid = evaluatePattern(target, static_cast<float>(o.proj.uv.x()), static_cast<float>(o.proj.uv.y()), w, 1.f,
                              points[i].pattern, static_cast<float>(tr.alpha), static_cast<float>(tr.beta), kernel,
                              o.res);
  }
}

}  // namespace rsvio
