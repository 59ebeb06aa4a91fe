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
    for (size_t i = 0; i < uv0.size(); ++i) {
      if (!valid[i]) continue;
      PatternHost host;
      if (!makePatternHost(img, static_cast<float>(cell[i].x()), static_cast<float>(cell[i].y()), ro, &host)) continue;
      // Fixed in the world at the host row's capture time (eq. 6 at t(v_h), eq. 7).
      const double t_h = timing_.rowTime(uv0[i].y());
      const Vec3 Z_c = bearing.col(static_cast<Eigen::Index>(i)) / idepth[i];
      const Vec3 Z = t_h == 0.0 ? Z_c : Vec3(SE3d::exp(-ref_.twist * t_h) * Z_c);
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

void FrameTracker::evaluate(const ImageLevel& img, int level, const RsFrame& target, const AffineBrightness& aff,
                            double exposure_ratio, double cutoff, bool linearize, Linearization& out) const {
  LevelPoints& L = *levels_[static_cast<size_t>(level)];
  const double alpha = exposure_ratio * std::exp(aff.a - ref_.affine.a);
  const double beta = aff.b - alpha * ref_.affine.b;
  const ResidualKernel kernel(options_.residual);
  const float inv_scale = 1.f / img.scale();
  const float cut = static_cast<float>(cutoff);
  const float sat_energy_unit = huberEnergy(cut, kernel.huber);
  const bool global = timing_.dtDv() == 0.0;
  const Eigen::Matrix3d R = target.T_c_w0.rotationMatrix();
  const Vec3 t = target.T_c_w0.translation();
  const float warp[4] = {1.f, 0.f, 0.f, 1.f};

  auto runBlock = [&](int bi) {
    Block& B = L.blocks[static_cast<size_t>(bi)];
    Linearization& acc = B.lin;
    acc.setZero();
    const Eigen::Index n = B.X_w.cols();
    // Geometry of the block: uv (level 0) and d uv / d T0 (left perturbation).
    if (global) {
      B.P.resize(3, n);
      for (Eigen::Index i = 0; i < n; ++i) B.P.col(i) = R * B.X_w.col(i) + t;
      camera_.project(B.P, B.uv, B.valid, linearize ? &B.J : nullptr);
    } else {
      RsProjectionOptions po;
      po.jacobians = linearize;
      projectRollingShutter(camera_, timing_, target, B.X_w, B.proj, po);
    }
    PatternResidual res;
    for (Eigen::Index i = 0; i < n; ++i) {
      Vec2 uv;
      if (global) {
        if (!B.valid[static_cast<size_t>(i)]) continue;
        uv = B.uv.col(i);
      } else {
        const RsProjection& pr = B.proj[static_cast<size_t>(i)];
        if (!pr.valid) continue;
        uv = pr.uv;
      }
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
      const Mat26& D = global ? Mat26(B.J[static_cast<size_t>(i)] * dLeftAction(B.P.col(i)))
                              : B.proj[static_cast<size_t>(i)].d_uv_d_T0;
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
    }
  };
  runner_->run(static_cast<int>(L.blocks.size()), runBlock);

  out.setZero();
  for (const Block& B : L.blocks) out.add(B.lin);  // fixed order: identical for any thread count
  // Mirror the upper triangle that was accumulated.
  for (int i = 0; i < 8; ++i)
    for (int j = i + 1; j < 8; ++j) out.H(j, i) = out.H(i, j);
}

FrameTracker::LevelEnergy FrameTracker::levelEnergy(const ImagePyramid& frame, const TrackingFrame& info, int level,
                                                    const SE3d& T_c_w, const AffineBrightness& affine) const {
  if (!hasReference()) throw Error("FrameTracker::levelEnergy: no reference keyframe");
  Linearization lin;
  RsFrame target{T_c_w, info.twist};
  evaluate(frame.level(level), level, target, affine, exposureRatio(ref_.exposure_ms, info.exposure_ms),
           options_.cutoff_th, false, lin);
  LevelEnergy e;
  e.energy = lin.energy;
  e.num_terms = lin.num_terms;
  e.num_saturated = lin.num_saturated;
  e.num_points = lin.num_points;
  return e;
}

}  // namespace rsvio
