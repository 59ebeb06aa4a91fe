// Frame tracker (contract in rsvio/frontend/frame_tracker.h): reference set-up, energy and normal
// equations per level. The Levenberg-Marquardt loop and the guesses are in frame_tracker_solve.cpp.
#include <algorithm>
#include <cmath>

#include "frame_tracker_internal.h"
#include "rsvio/core/error.h"
#include "rsvio/interfaces/camera.h"

namespace rsvio {

FrameTracker::FrameTracker(const TrackerOptions& options, const CameraModel& camera, const RowTiming& timing)
    : options_(options), camera_(camera), timing_(timing), runner_(new BlockRunner(std::clamp(options.threads, 1, 2))) {
  last_rmse_.fill(std::nan(""));
}

FrameTracker::~FrameTracker() = default;

int FrameTracker::numReferencePoints(int level) const {
  return level >= 0 && level < static_cast<int>(levels_.size()) ? levels_[level]->n : 0;
}

void FrameTracker::setReference(const TrackingReference& reference) {
  if (!reference.pyramid || reference.pyramid->numLevels() == 0)
    throw Error("FrameTracker::setReference: reference keyframe has no image pyramid");
  ref_ = reference;
  first_rmse_ = std::nan("");
  const ImagePyramid& pyr = *ref_.pyramid;
  const int num_levels = std::min(options_.max_levels, pyr.numLevels());
  levels_.clear();
  const SE3d T_w_h0 = ref_.T_c_w.inverse();

  for (int l = 0; l < num_levels; ++l) {
    const ImageLevel& img = pyr.level(l);
    // Merge points per level pixel (DSO's makeCoarseDepthL0): weighted mean inverse depth.
    std::vector<double> sum_w(static_cast<size_t>(img.width()) * img.height(), 0.0);
    std::vector<double> sum_id(sum_w.size(), 0.0);
    for (const TrackingPoint& p : ref_.points) {
      if (!(p.idepth > 0.0) || !std::isfinite(p.idepth) || !(p.weight > 0.0)) continue;
      const int x = static_cast<int>(std::lround(img.toLevel(static_cast<float>(p.uv.x()))));
      const int y = static_cast<int>(std::lround(img.toLevel(static_cast<float>(p.uv.y()))));
      if (x < 0 || y < 0 || x >= img.width() || y >= img.height()) continue;
      sum_w[static_cast<size_t>(y) * img.width() + x] += p.weight;
      sum_id[static_cast<size_t>(y) * img.width() + x] += p.weight * p.idepth;
    }
    std::vector<Vec2> uv0;
    std::vector<double> idepth;
    std::vector<Eigen::Vector2i> cell;
    for (int y = 0; y < img.height(); ++y)
      for (int x = 0; x < img.width(); ++x) {
        const size_t i = static_cast<size_t>(y) * img.width() + x;
        if (sum_w[i] <= 0.0) continue;
        uv0.emplace_back(img.fromLevel(static_cast<float>(x)), img.fromLevel(static_cast<float>(y)));
        idepth.push_back(sum_id[i] / sum_w[i]);
        cell.emplace_back(x, y);
      }
    Eigen::Matrix2Xd uv(2, static_cast<Eigen::Index>(uv0.size()));
    for (size_t i = 0; i < uv0.size(); ++i) uv.col(static_cast<Eigen::Index>(i)) = uv0[i];
    Eigen::Matrix3Xd bearing;
    std::vector<uint8_t> valid;
    camera_.unproject(uv, bearing, valid, nullptr);

    auto L = std::make_unique<LevelPoints>();
    const ResidualOptions& ro = options_.residual;
    std::vector<Vec3> X;
    const TwistExp ref_exp(ref_.twist);
    const ReadoutRotation ref_ra(ref_.w_dot);
    for (size_t i = 0; i < uv0.size(); ++i) {
      if (!valid[i]) continue;
      PatternHost host;
      if (!makePatternHost(img, static_cast<float>(cell[i].x()), static_cast<float>(cell[i].y()), ro, &host)) continue;
      // Fixed in the world at the host row's capture time (eq. 6 at t(v_h), eq. 7).
      const double t_h = timing_.rowTime(uv0[i].y());
      const Vec3 Z_c = bearing.col(static_cast<Eigen::Index>(i)) / idepth[i];
      // With w_dot: T_h(t_h) = A(t_h) exp(xi t_h) T_h0, so Z = exp(-xi t_h) A^T Z_c.
      const Vec3 Z = t_h == 0.0 ? Z_c : ref_exp.apply(-t_h, ref_ra.A(t_h).transpose() * Z_c);
      X.push_back(T_w_h0 * Z);
      L->host.push_back(host);
      L->host_uv0.push_back(uv0[i]);
      L->host_point.push_back(bearing.col(static_cast<Eigen::Index>(i)) / idepth[i]);
    }
    L->n = static_cast<int>(X.size());
    const int nb = (L->n + kBlockPoints - 1) / kBlockPoints;
    L->blocks.resize(static_cast<size_t>(nb));
    for (int b = 0; b < nb; ++b) {
      const int begin = b * kBlockPoints;
      const int end = std::min(L->n, begin + kBlockPoints);
      Block& B = L->blocks[static_cast<size_t>(b)];
      B.begin = begin;
      B.X_w.resize(3, end - begin);
      for (int i = begin; i < end; ++i) B.X_w.col(i - begin) = X[static_cast<size_t>(i)];
    }
    levels_.push_back(std::move(L));
  }
}

void FrameTracker::resetRows() const {
  for (const auto& L : levels_)
    for (Block& B : L->blocks) B.row.clear();
}

// Projection of a block into the target with d uv / d T0 (left perturbation of the central pose).
// Global shutter: one batch projection. Rolling shutter: Newton on the row as rs_projection.h
// (v <- v + (pi_v - v) / (1 - a_v), a = J (xi_v + xi_w x P) dt/dv) with only the Jacobian the tracker
// needs, d uv / d T0 = M J R(xi t) [I, -[P0]x], M = (I - a e_v^T)^-1, and the row of the previous
// evaluation as the start (reset for every guess).
//
// With `rate` the block also gets E = d uv / d w (w the twist's rotation, rad/s): at the row time t,
// exp((xi + (0; dw)) t) P0 = P + t dw x P up to the left Jacobian of xi t (|w t| ~ 1e-2 rad over a
// readout: a 1 % error in a Gauss-Newton direction, not in the residual), so d P / d w = -t [P]x, and
// the row's dependence enters as for D: E = M J (-t [P]x).
void FrameTracker::projectBlock(Block& B, const RsFrame& target, bool linearize, bool rate) const {
  const Eigen::Index n = B.X_w.cols();
  const Eigen::Matrix3d R = target.T_c_w0.rotationMatrix();
  const Vec3 t = target.T_c_w0.translation();
  B.P0.resize(3, n);
  for (Eigen::Index i = 0; i < n; ++i) B.P0.col(i) = R * B.X_w.col(i) + t;
  if (linearize) B.D.resize(static_cast<size_t>(n));
  const double c = timing_.dtDv();
  rate = rate && linearize && c != 0.0;
  if (rate) B.E.resize(static_cast<size_t>(n));
  if (c == 0.0) {
    camera_.project(B.P0, B.uv, B.valid, linearize ? &B.J : nullptr);
    if (linearize)
      for (Eigen::Index i = 0; i < n; ++i)
        if (B.valid[static_cast<size_t>(i)]) B.D[static_cast<size_t>(i)] = B.J[static_cast<size_t>(i)] * dLeftAction(B.P0.col(i));
    return;
  }
  const Vec3 xi_v = target.xi.head<3>(), xi_w = target.xi.tail<3>();
  const TwistExp ex(target.xi);
  const ReadoutRotation ra(target.w_dot);
  const bool acc = !ra.zero();  // RsFrame::w_dot: P = A(t) exp(xi t) P0
  if (B.row.size() != static_cast<size_t>(n)) B.row.assign(static_cast<size_t>(n), timing_.y0);
  B.uv.resize(2, n);
  B.valid.assign(static_cast<size_t>(n), 0);
  B.active.resize(static_cast<size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) B.active[static_cast<size_t>(i)] = static_cast<int>(i);
  for (int it = 0; it < kRowMaxIterations && !B.active.empty(); ++it) {
    const Eigen::Index m = static_cast<Eigen::Index>(B.active.size());
    B.P.resize(3, m);
    for (Eigen::Index k = 0; k < m; ++k) {
      const int i = B.active[static_cast<size_t>(k)];
      const double ti = timing_.rowTime(B.row[static_cast<size_t>(i)]);
      B.P.col(k) = ex.apply(ti, Vec3(B.P0.col(i)));  // eq. 6 at the row's time (eq. 7)
      if (acc) B.P.col(k) = ra.A(ti) * B.P.col(k);
    }
    camera_.project(B.P, B.uv_a, B.valid_a, &B.J);
    B.still.clear();
    for (Eigen::Index k = 0; k < m; ++k) {
      const int i = B.active[static_cast<size_t>(k)];
      const size_t si = static_cast<size_t>(i);
      if (!B.valid_a[static_cast<size_t>(k)]) continue;
      const Jac23& J = B.J[static_cast<size_t>(k)];
      const Vec3 Pk = B.P.col(k);
      // d P / d t: xi^ P, or with w_dot g x P + A (xi_v + xi_w x A^T P)
      const double tk = timing_.rowTime(B.row[si]);
      const Mat3 Ak = acc ? ra.A(tk) : Mat3::Identity();
      const Vec3 dPdt = acc ? Vec3(ra.g(tk).cross(Pk) + Ak * (xi_v + xi_w.cross(Ak.transpose() * Pk)))
                            : Vec3(xi_v + xi_w.cross(Pk));
      const Vec2 a = J * dPdt * c;
      const double denom = 1.0 - a.y();
      if (std::abs(denom) < 1e-3) continue;  // no unique row
      const double res = B.uv_a(1, k) - B.row[si];
      const double step = res / denom;  // Newton step on the row
      if (std::abs(step) > kRowLinearStepPx) {
        B.row[si] += step;
        B.still.push_back(i);
        continue;
      }
      // Small step: the solution is the linearisation uv + a step (error ~ step^2 x the curvature of
      // the projection in time: < 1e-6 px for 0.05 rows at any realistic motion), which saves a camera
      // call per point in most LM steps.
      const double ti = timing_.rowTime(B.row[si]);
      B.row[si] += step;
      B.uv.col(i) = B.uv_a.col(k) + a * step;
      B.valid[si] = 1;
      if (linearize) {
        Mat26 D = acc ? Mat26(J * (Ak * ex.rotation(ti)) * dLeftAction(B.P0.col(i)))
                      : Mat26(J * ex.rotation(ti) * dLeftAction(B.P0.col(i)));
        const double inv = 1.0 / denom;
        D.row(0) += (a.x() * inv) * D.row(1);
        D.row(1) *= inv;
        B.D[si] = D;
        if (rate) {
          Jac23 E = J * (-ti * SO3d::hat(Pk));
          E.row(0) += (a.x() * inv) * E.row(1);
          E.row(1) *= inv;
          B.E[si] = E;
        }
      }
    }
    B.active.swap(B.still);
  }
  for (int i : B.active) B.row[static_cast<size_t>(i)] = timing_.y0;  // not converged: restart next time
}

void FrameTracker::evaluate(const ImageLevel& img, int level, const RsFrame& target, const AffineBrightness& aff,
                            double exposure_ratio, double cutoff, bool linearize, Linearization& out, bool rate) const {
  LevelPoints& L = *levels_[static_cast<size_t>(level)];
  const double alpha = exposure_ratio * std::exp(aff.a - ref_.affine.a);
  const double beta = aff.b - alpha * ref_.affine.b;
  const ResidualKernel kernel(options_.residual);
  const float inv_scale = 1.f / img.scale();
  const float cut = static_cast<float>(cutoff);
  const float sat_energy_unit = huberEnergy(cut, kernel.huber);
  const float warp[4] = {1.f, 0.f, 0.f, 1.f};
  const double explained2 = options_.explained_residual * options_.explained_residual;
  rate = rate && linearize && timing_.dtDv() != 0.0;  // projectBlock forms E under the same condition

  auto runBlock = [&](int bi) {
    Block& B = L.blocks[static_cast<size_t>(bi)];
    Linearization& acc = B.lin;
    acc.setZero();
    const Eigen::Index n = B.X_w.cols();
    projectBlock(B, target, linearize, rate);  // uv (level 0), d uv / d T0 (and d uv / d w)
    PatternResidual res;
    for (Eigen::Index i = 0; i < n; ++i) {
      if (!B.valid[static_cast<size_t>(i)]) continue;
      const Vec2 uv = B.uv.col(i);
      const float u = img.toLevel(static_cast<float>(uv.x()));
      const float v = img.toLevel(static_cast<float>(uv.y()));
      const PatternHost& host = L.host[static_cast<size_t>(B.begin + i)];
      if (!evaluatePattern(img, u, v, warp, inv_scale, host, static_cast<float>(alpha), static_cast<float>(beta),
                           kernel, res))
        continue;
      ++acc.num_points;
      // Per-point sums of the 8 pattern pixels, then one D^T G D (DSO's factorisation).
      double gxx = 0, gxy = 0, gyy = 0, grx = 0, gry = 0, gcx = 0, gcy = 0, g1x = 0, g1y = 0;
      double cc = 0, c1 = 0, w1 = 0, cr = 0, r1 = 0;
      if (!linearize) {
        // Explained point (contract): residual energy below explained_residual^2 x the spread of the
        // target's pattern intensities I_k = r_k + alpha c_k + beta about their mean.
        double si = 0, si2 = 0, sr2 = 0;
        for (int k = 0; k < kPatternSize; ++k) {
          const double r = res.r[k], I = r + alpha * host.color[k] + beta;
          si += I;
          si2 += I * I;
          sr2 += r * r;
        }
        if (sr2 < explained2 * (si2 - si * si / kPatternSize)) ++acc.num_explained;
      }
      for (int k = 0; k < kPatternSize; ++k) {
        ++acc.num_terms;
        const float r = res.r[k];
        if (std::abs(r) > cut) {
          ++acc.num_saturated;
          acc.energy += res.wg2[k] * sat_energy_unit;
          continue;
        }
        acc.energy += res.wg2[k] * huberEnergy(r, kernel.huber);
        if (!linearize) continue;
        const double w = res.w[k], gx = res.gx[k], gy = res.gy[k];
        const double c = -alpha * (host.color[k] - ref_.affine.b);  // d r / d a_j
        gxx += w * gx * gx;
        gxy += w * gx * gy;
        gyy += w * gy * gy;
        grx += w * gx * r;
        gry += w * gy * r;
        gcx += w * gx * c;
        gcy += w * gy * c;
        g1x -= w * gx;
        g1y -= w * gy;
        cc += w * c * c;
        c1 -= w * c;
        w1 += w;
        cr += w * c * r;
        r1 -= w * r;
      }
      if (!linearize) continue;
      const Mat26& D = B.D[static_cast<size_t>(i)];
      Eigen::Matrix2d G;
      G << gxx, gxy, gxy, gyy;
      acc.H.topLeftCorner<6, 6>().noalias() += D.transpose() * G * D;
      acc.H.block<6, 1>(0, 6).noalias() += D.transpose() * Vec2(gcx, gcy);
      acc.H.block<6, 1>(0, 7).noalias() += D.transpose() * Vec2(g1x, g1y);
      acc.H(6, 6) += cc;
      acc.H(6, 7) += c1;
      acc.H(7, 7) += w1;
      acc.b.head<6>().noalias() += D.transpose() * Vec2(grx, gry);
      acc.b(6) += cr;
      acc.b(7) += r1;
      if (rate) {
        const Jac23& E = B.E[static_cast<size_t>(i)];
        acc.H.block<6, 3>(0, 8).noalias() += D.transpose() * G * E;
        acc.H.block<1, 3>(6, 8).noalias() += Vec2(gcx, gcy).transpose() * E;
        acc.H.block<1, 3>(7, 8).noalias() += Vec2(g1x, g1y).transpose() * E;
        acc.H.block<3, 3>(8, 8).noalias() += E.transpose() * G * E;
        acc.b.tail<3>().noalias() += E.transpose() * Vec2(grx, gry);
      }
    }
  };
  runner_->run(static_cast<int>(L.blocks.size()), runBlock);

  out.setZero();
  for (const Block& B : L.blocks) out.add(B.lin);  // fixed order: identical for any thread count
  // Mirror the upper triangle that was accumulated.
  for (int i = 0; i < kTrackDim; ++i)
    for (int j = i + 1; j < kTrackDim; ++j) out.H(j, i) = out.H(i, j);
}

void FrameTracker::projectReference(int level, const SE3d& T_c_w, const Vec6& twist, Eigen::Matrix2Xd* uv,
                                    std::vector<uint8_t>* valid, std::vector<Eigen::Matrix<double, 2, 6>>* d_uv_d_T,
                                    Eigen::Matrix3Xd* X_w, const Vec3& w_dot,
                                    std::vector<Eigen::Matrix<double, 2, 3>>* d_uv_d_w) const {
  if (!hasReference()) throw Error("FrameTracker::projectReference: no reference keyframe");
  LevelPoints& L = *levels_.at(static_cast<size_t>(level));
  resetRows();
  uv->resize(2, L.n);
  if (X_w) X_w->resize(3, L.n);
  valid->assign(static_cast<size_t>(L.n), 0);
  if (d_uv_d_T) d_uv_d_T->assign(static_cast<size_t>(L.n), Mat26::Zero());
  const bool rate = d_uv_d_T && d_uv_d_w && timing_.dtDv() != 0.0;
  if (d_uv_d_w) d_uv_d_w->assign(static_cast<size_t>(L.n), Jac23::Zero());
  for (Block& B : L.blocks) {
    projectBlock(B, RsFrame{T_c_w, twist, w_dot}, d_uv_d_T != nullptr, rate);
    for (Eigen::Index i = 0; i < B.X_w.cols(); ++i) {
      const size_t j = static_cast<size_t>(B.begin + i);
      if (X_w) X_w->col(static_cast<Eigen::Index>(j)) = B.X_w.col(i);
      uv->col(static_cast<Eigen::Index>(j)) = B.uv.col(i);
      (*valid)[j] = B.valid[static_cast<size_t>(i)];
      if (d_uv_d_T && B.valid[static_cast<size_t>(i)]) (*d_uv_d_T)[j] = B.D[static_cast<size_t>(i)];
      if (rate && B.valid[static_cast<size_t>(i)]) (*d_uv_d_w)[j] = B.E[static_cast<size_t>(i)];
    }
  }
}

FrameTracker::LevelEnergy FrameTracker::levelEnergy(const ImagePyramid& frame, const TrackingFrame& info, int level,
                                                    const SE3d& T_c_w, const AffineBrightness& affine) const {
  if (!hasReference()) throw Error("FrameTracker::levelEnergy: no reference keyframe");
  Linearization lin;
  resetRows();
  RsFrame target{T_c_w, info.twist, info.w_dot};
  evaluate(frame.level(level), level, target, affine, exposureRatio(ref_.exposure_ms, info.exposure_ms),
           options_.cutoff_th, false, lin);
  LevelEnergy e;
  e.energy = lin.energy;
  e.num_terms = lin.num_terms;
  e.num_saturated = lin.num_saturated;
  e.num_points = lin.num_points;
  e.num_explained = lin.num_explained;
  return e;
}

}  // namespace rsvio
