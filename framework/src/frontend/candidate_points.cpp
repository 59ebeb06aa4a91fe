// Candidate points and their epipolar search (contract in rsvio/frontend/candidate_points.h).
#include "rsvio/frontend/candidate_points.h"

#include <algorithm>
#include <cmath>

#include "rsvio/lie/se3.h"

namespace rsvio {

const char* candidateStatusName(CandidateStatus s) {
  switch (s) {
    case CandidateStatus::Uninitialized: return "uninitialized";
    case CandidateStatus::Good: return "good";
    case CandidateStatus::Skipped: return "skipped";
    case CandidateStatus::BadCondition: return "bad_condition";
    case CandidateStatus::Outlier: return "outlier";
    case CandidateStatus::OutOfBounds: return "out_of_bounds";
  }
  return "?";
}

bool CandidatePoint::readyForActivation(const CandidateOptions& o) const {
  const bool traced = status == CandidateStatus::Good || status == CandidateStatus::Skipped ||
                      status == CandidateStatus::BadCondition;
  return traced && num_good > 0 && last_interval_px < o.max_activation_interval_px && quality > o.min_quality &&
         hasDepth() && idepth_min + idepth_max > 0.0;
}

CandidateTracer::CandidateTracer(const CandidateOptions& options, const ResidualOptions& residual,
                                 const CameraModel& camera, const RowTiming& timing)
    : options_(options), residual_(residual), camera_(camera), timing_(timing) {}

std::vector<CandidatePoint> CandidateTracer::create(const ImageLevel& img, const std::vector<Vec2>& pixels) const {
  Eigen::Matrix2Xd q(2, static_cast<Eigen::Index>(pixels.size()));
  for (size_t i = 0; i < pixels.size(); ++i) q.col(static_cast<Eigen::Index>(i)) = pixels[i];
  Eigen::Matrix3Xd b;
  std::vector<uint8_t> valid;
  std::vector<Jac32> J;
  camera_.unproject(q, b, valid, &J);
  std::vector<CandidatePoint> out;
  out.reserve(pixels.size());
  const double energy_th = residual_.outlierEnergy();
  for (size_t i = 0; i < pixels.size(); ++i) {
    if (!valid[i]) continue;
    CandidatePoint c;
    c.uv = pixels[i];
    c.bearing = b.col(static_cast<Eigen::Index>(i));
    c.d_bearing_d_uv = J[i];
    if (!makePatternHost(img, static_cast<float>(c.uv.x()), static_cast<float>(c.uv.y()), residual_, &c.pattern))
      continue;
    float s[4];
    for (int k = 0; k < kPatternSize; ++k) {
      img.sample(static_cast<float>(c.uv.x() + kPattern[k][0]), static_cast<float>(c.uv.y() + kPattern[k][1]), s);
      const Eigen::Vector2d g(s[1], s[2]);
      c.grad_h += g * g.transpose();
    }
    c.energy_th = energy_th;
    out.push_back(c);
  }
  return out;
}

namespace {

// Per-candidate working data of one trace() call.
struct Work {
  bool active = false;
  Eigen::Matrix3d R;     // target-from-host rotation (at the host row time and the assumed target time)
  Vec3 t;                // target-from-host translation
  Vec3 Rb;               // R * bearing: the direction of X(rho) = Rb + rho t (up to scale)
  double rho0 = 0, rho1 = 0;
  bool infinite = false;
  Vec2 uv0, uv1;
  Jac23 J0;
  double dist = 0, err = 0, shift = 0;
  int steps = 0;
  int first_sample = 0;
  Vec3 n0, n1;           // unit directions at rho0, rho1
  Vec2 best_uv, dir;
};

SE3d poseAt(const RsFrame& f, double t) { return rsPoseAt(f, t); }

// rho with Rb + rho t parallel to the bearing d (closest point on the host ray, in the target frame).
double rhoForBearing(const Vec3& d, const Vec3& Rb, const Vec3& t) {
  const Vec3 a = d.cross(Rb), c = d.cross(t);
  const double cc = c.squaredNorm();
  if (!(cc > 1e-20)) return std::nan("");
  return -a.dot(c) / cc;
}

}  // namespace

TraceStats CandidateTracer::trace(std::vector<CandidatePoint>& points, const CandidateFrame& host,
                                  const CandidateFrame& target, const ImageLevel& img) const {
  TraceStats stats;
  const size_t n = points.size();
  const double max_pix = options_.max_search_frac * (img.width() + img.height());
  const float margin = static_cast<float>(kPatternRadius + 2);
  const double exposure_ratio =
      (host.exposure_ms > 0 && target.exposure_ms > 0) ? target.exposure_ms / host.exposure_ms : 1.0;
  const AffineTransfer tr = affineTransfer(host.affine, target.affine, exposure_ratio);
  const float alpha = static_cast<float>(tr.alpha), beta = static_cast<float>(tr.beta);
  const float huber = static_cast<float>(residual_.huber_th);
  std::vector<Work> work(n);

  auto finish = [&](CandidatePoint& c, CandidateStatus s) {
    c.status = s;
    switch (s) {
      case CandidateStatus::Good: ++stats.good; break;
      case CandidateStatus::Skipped: ++stats.skipped; break;
      case CandidateStatus::BadCondition: ++stats.bad_condition; break;
      case CandidateStatus::Outlier: ++stats.outlier; break;
      case CandidateStatus::OutOfBounds: ++stats.out_of_bounds; break;
      default: break;
    }
  };
  auto setOob = [&](CandidatePoint& c) {
    c.last_uv = Vec2(-1, -1);
    c.last_interval_px = 0;
    finish(c, CandidateStatus::OutOfBounds);
  };

  // ---- A: relative geometry and the end points of the search (one batch projection).
  Eigen::Matrix3Xd Q(3, static_cast<Eigen::Index>(2 * n));
  for (size_t i = 0; i < n; ++i) {
    CandidatePoint& c = points[i];
    Work& w = work[i];
    Q.col(static_cast<Eigen::Index>(2 * i)).setConstant(std::nan(""));
    Q.col(static_cast<Eigen::Index>(2 * i + 1)).setConstant(std::nan(""));
    if (c.status == CandidateStatus::OutOfBounds) {
      ++stats.already_out;
      continue;
    }
    const double t_h = timing_.rowTime(c.uv.y());
    const double t_t = c.num_good > 0 ? c.last_row_time_s : t_h;
    const SE3d T_th = poseAt(target.pose, t_t) * poseAt(host.pose, t_h).inverse();
    w.R = T_th.rotationMatrix();
    w.t = T_th.translation();
    w.Rb = w.R * c.bearing;
    w.rho0 = std::max(0.0, c.idepth_min);
    w.infinite = !std::isfinite(c.idepth_max);
    w.rho1 = w.infinite ? w.rho0 : c.idepth_max;
    Q.col(static_cast<Eigen::Index>(2 * i)) = w.Rb + w.rho0 * w.t;
    Q.col(static_cast<Eigen::Index>(2 * i + 1)) = w.Rb + w.rho1 * w.t;
    w.active = true;
  }
  Eigen::Matrix2Xd uvQ;
  std::vector<uint8_t> vQ;
  std::vector<Jac23> JQ;
  camera_.project(Q, uvQ, vQ, &JQ);

  // ---- B: search length, conditioning, samples (one batch projection).
  int total_samples = 0;
  for (size_t i = 0; i < n; ++i) {
    CandidatePoint& c = points[i];
    Work& w = work[i];
    if (!w.active) continue;
    w.active = false;
    w.uv0 = uvQ.col(static_cast<Eigen::Index>(2 * i));
    w.J0 = JQ[2 * i];
    if (!vQ[2 * i] || !img.inside(static_cast<float>(w.uv0.x()), static_cast<float>(w.uv0.y()), margin)) {
      setOob(c);
      continue;
    }
    // DSO: a point whose distance changes by more than 0.75..1.5 between the views is dropped.
    if (w.rho0 > 0.0) {
      const double ratio = (w.Rb + w.rho0 * w.t).norm();
      if (!(ratio > 0.75 && ratio < 1.5)) {
        setOob(c);
        continue;
      }
    }
    if (w.infinite) {
      const Vec2 g = w.J0 * w.t;  // pixels per unit of rho at rho0
      if (!(g.norm() > 1e-12)) {
        finish(c, CandidateStatus::BadCondition);  // no baseline: nothing to triangulate
        continue;
      }
      w.rho1 = w.rho0 + max_pix / g.norm();
      w.dist = max_pix;
      w.dir = g.normalized();
    } else {
      w.uv1 = uvQ.col(static_cast<Eigen::Index>(2 * i + 1));
      if (!vQ[2 * i + 1] || !img.inside(static_cast<float>(w.uv1.x()), static_cast<float>(w.uv1.y()), margin)) {
        setOob(c);
        continue;
      }
      w.dist = (w.uv1 - w.uv0).norm();
      if (w.dist < options_.slack_interval_px) {
        c.last_uv = 0.5 * (w.uv0 + w.uv1);
        c.last_interval_px = w.dist;
        finish(c, CandidateStatus::Skipped);
        continue;
      }
      w.dir = (w.uv1 - w.uv0) / w.dist;
    }
    // Error bound from the host gradients along and across the search direction (DSO).
    const Vec2 perp(w.dir.y(), -w.dir.x());
    const double a = w.dir.dot(c.grad_h * w.dir), b = perp.dot(c.grad_h * perp);
    w.err = 0.2 + 0.2 * (a + b) / a;
    if (!std::isfinite(w.err)) w.err = 10.0;
    if (w.err * options_.min_improvement > w.dist && !w.infinite) {
      c.last_uv = 0.5 * (w.uv0 + w.uv1);
      c.last_interval_px = w.dist;
      finish(c, CandidateStatus::BadCondition);
      continue;
    }
    w.err = std::min(w.err, 10.0);
    // Sample directions between the unit directions at rho0 and rho1; s in units of the full length.
    w.n0 = (w.Rb + w.rho0 * w.t).normalized();
    w.n1 = (w.Rb + w.rho1 * w.t).normalized();
    const double len = std::min(w.dist, max_pix);
    w.steps = std::min(100, static_cast<int>(1.9999 + len / options_.step_px));
    w.shift = w.uv0.x() * 1000.0 - std::floor(w.uv0.x() * 1000.0);  // DSO's deterministic sub-step shift
    w.first_sample = total_samples;
    total_samples += w.steps;
    w.active = true;
  }
  Eigen::Matrix3Xd S(3, total_samples);
  for (size_t i = 0; i < n; ++i) {
    const Work& w = work[i];
    if (!w.active) continue;
    for (int k = 0; k < w.steps; ++k) {
      const double s = (k - w.shift) * options_.step_px / w.dist;
      S.col(w.first_sample + k) = (1.0 - s) * w.n0 + s * w.n1;
    }
  }
  Eigen::Matrix2Xd uvS;
  std::vector<uint8_t> vS;
  camera_.project(S, uvS, vS, nullptr);

  // ---- C: discrete search, second best, Gauss-Newton along the curve.
  std::vector<float> errors;
  Eigen::Matrix2Xd M(2, static_cast<Eigen::Index>(2 * n));
  M.setZero();
  for (size_t i = 0; i < n; ++i) {
    CandidatePoint& c = points[i];
    Work& w = work[i];
    if (!w.active) continue;
    // Pattern warp d p' / d uv_h at the start of the search (DSO rotates the pattern by KRKi's 2x2).
    // With X_t = q / rho, q = Rb + rho t: J(X_t) = rho J(q), so d p' / d uv_h = J(q) R d b / d uv_h.
    const Eigen::Matrix2d W = w.J0 * w.R * c.d_bearing_d_uv;
    Eigen::Vector2f off[kPatternSize];
    for (int k = 0; k < kPatternSize; ++k)
      off[k] = (W * Vec2(kPattern[k][0], kPattern[k][1])).cast<float>();
    auto patternEnergy = [&](float u, float v) {
      float e = 0.f;
      for (int k = 0; k < kPatternSize; ++k) {
        const float x = u + off[k].x(), y = v + off[k].y();
        if (!img.inside(x, y, 1.f)) {
          e += 1e5f;
          continue;
        }
        const float r = img.sampleIntensity(x, y) - (alpha * c.pattern.color[k] + beta);
        e += huberEnergy(r, huber);
      }
      return e;
    };
    errors.assign(static_cast<size_t>(w.steps), 1e5f * kPatternSize);
    int best = -1;
    float best_e = 1e10f;
    for (int k = 0; k < w.steps; ++k) {
      const Eigen::Index col = w.first_sample + k;
      if (!vS[static_cast<size_t>(col)]) continue;
      const float e = patternEnergy(static_cast<float>(uvS(0, col)), static_cast<float>(uvS(1, col)));
      errors[static_cast<size_t>(k)] = e;
      if (e < best_e) {
        best_e = e;
        best = k;
      }
    }
    if (best < 0) {
      setOob(c);
      w.active = false;
      continue;
    }
    float second = 1e10f;
    for (int k = 0; k < w.steps; ++k)
      if ((k < best - options_.second_best_radius || k > best + options_.second_best_radius) &&
          errors[static_cast<size_t>(k)] < second)
        second = errors[static_cast<size_t>(k)];
    const double q = second / std::max(best_e, 1e-6f);
    if (q < c.quality || w.steps > 10) c.quality = q;

    // Tangent of the curve at the best sample.
    const int k0 = std::max(0, best - 1), k1 = std::min(w.steps - 1, best + 1);
    Vec2 tangent = uvS.col(w.first_sample + k1) - uvS.col(w.first_sample + k0);
    w.dir = (k1 > k0 && tangent.norm() > 1e-9) ? Vec2(tangent.normalized()) : w.dir;
    Vec2 p = uvS.col(w.first_sample + best);
    // Gauss-Newton on the position along the tangent (DSO): weighted energy for acceptance.
    Vec2 p_bak = p;
    double step_back = 0.0;
    double best_energy = 1e5;
    for (int it = 0; it < options_.gn_iterations; ++it) {
      double H = 1.0, bsum = 0.0, energy = 0.0;
      float s4[4];
      for (int k = 0; k < kPatternSize; ++k) {
        const float x = static_cast<float>(p.x()) + off[k].x(), y = static_cast<float>(p.y()) + off[k].y();
        if (!img.inside(x, y, 1.f)) {
          energy += 1e5;
          continue;
        }
        img.sample(x, y, s4);
        const double r = s4[0] - (alpha * c.pattern.color[k] + beta);
        const double d = w.dir.x() * s4[1] + w.dir.y() * s4[2];
        const double hw = huberWeight(static_cast<float>(r), huber);
        H += hw * d * d;
        bsum += hw * r * d;
        energy += c.pattern.weight[k] * c.pattern.weight[k] * hw * r * r * (2.0 - hw);
      }
      if (energy > best_energy) {
        step_back *= 0.5;
        p = p_bak + step_back * w.dir;
      } else {
        double step = -bsum / H;
        step = std::clamp(std::isfinite(step) ? step : 0.0, -0.5, 0.5);
        p_bak = p;
        step_back = step;
        p += step * w.dir;
        best_energy = energy;
      }
      if (std::abs(step_back) < options_.gn_threshold_px) break;
    }
    if (!(best_energy < c.energy_th * options_.outlier_slack)) {
      c.last_uv = Vec2(-1, -1);
      c.last_interval_px = 0;
      if (c.status == CandidateStatus::Outlier) {
        finish(c, CandidateStatus::OutOfBounds);
      } else {
        finish(c, CandidateStatus::Outlier);
      }
      w.active = false;
      continue;
    }
    w.best_uv = p;
    M.col(static_cast<Eigen::Index>(2 * i)) = p - w.err * w.dir;
    M.col(static_cast<Eigen::Index>(2 * i + 1)) = p + w.err * w.dir;
  }

  // ---- D: the new interval from the match +- err px (one batch unprojection).
  Eigen::Matrix3Xd B;
  std::vector<uint8_t> vB;
  camera_.unproject(M, B, vB, nullptr);
  for (size_t i = 0; i < n; ++i) {
    CandidatePoint& c = points[i];
    Work& w = work[i];
    if (!w.active) continue;
    const double t_match = timing_.rowTime(w.best_uv.y());
    if (timing_.dtDv() != 0.0) {
      const SE3d T_th = poseAt(target.pose, t_match) * poseAt(host.pose, timing_.rowTime(c.uv.y())).inverse();
      w.R = T_th.rotationMatrix();
      w.t = T_th.translation();
      w.Rb = w.R * c.bearing;
    }
    double r0 = std::nan(""), r1 = std::nan("");
    if (vB[2 * i] && vB[2 * i + 1]) {
      r0 = rhoForBearing(B.col(static_cast<Eigen::Index>(2 * i)), w.Rb, w.t);
      r1 = rhoForBearing(B.col(static_cast<Eigen::Index>(2 * i + 1)), w.Rb, w.t);
    }
    if (r0 > r1) std::swap(r0, r1);
    if (!std::isfinite(r0) || !std::isfinite(r1) || r1 < 0.0) {
      c.last_uv = Vec2(-1, -1);
      c.last_interval_px = 0;
      finish(c, CandidateStatus::Outlier);
      continue;
    }
    c.idepth_min = std::max(0.0, r0);
    c.idepth_max = r1;
    c.last_uv = w.best_uv;
    c.last_interval_px = 2.0 * w.err;
    c.last_row_time_s = t_match;
    ++c.num_good;
    finish(c, CandidateStatus::Good);
  }
  return stats;
}

ParamTable CandidateOptions::paramTable() {
  const CandidateOptions d;
  return {
      paramDouble("trace_step_px", d.step_px, 0.25, 10.0, "px", "step of the epipolar search (DSO: 1)"),
      paramDouble("trace_max_search_frac", d.max_search_frac, 0.001, 1.0, "",
                  "longest epipolar search as a fraction of width + height (DSO: 0.027)"),
      paramInt("trace_gn_iterations", d.gn_iterations, 0, 20, "", "Gauss-Newton refinements of a match (DSO: 3)"),
      paramDouble("trace_slack_interval_px", d.slack_interval_px, 0.0, 100.0, "px",
                  "skip the search when the interval is already this short (DSO: 1.5)"),
      paramDouble("trace_min_improvement", d.min_improvement, 1.0, 100.0, "",
                  "search only if it can shrink the interval by this factor (DSO: 2)"),
      paramDouble("trace_outlier_slack", d.outlier_slack, 1.0, 10.0, "",
                  "factor on the outlier energy threshold for a match (DSO: 1.2)"),
      paramDouble("trace_min_quality", d.min_quality, 1.0, 1000.0, "",
                  "activation: second-best / best energy at least this (DSO: 3)"),
      paramDouble("trace_max_activation_interval_px", d.max_activation_interval_px, 0.1, 1000.0, "px",
                  "activation: last search interval shorter than this (DSO: 8)"),
  };
}

CandidateOptions CandidateOptions::fromParams(const Params& p) {
  CandidateOptions o;
  o.step_px = p.getDouble("trace_step_px");
  o.max_search_frac = p.getDouble("trace_max_search_frac");
  o.gn_iterations = static_cast<int>(p.getInt("trace_gn_iterations"));
  o.slack_interval_px = p.getDouble("trace_slack_interval_px");
  o.min_improvement = p.getDouble("trace_min_improvement");
  o.outlier_slack = p.getDouble("trace_outlier_slack");
  o.min_quality = p.getDouble("trace_min_quality");
  o.max_activation_interval_px = p.getDouble("trace_max_activation_interval_px");
  return o;
}

}  // namespace rsvio
