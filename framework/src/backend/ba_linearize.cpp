// Bundle adjustment, linearisation: structure of the window, residuals and Jacobians per host-target
// pair, keyframe priors and window terms (contract in rsvio/backend/bundle_adjustment.h); the
// accumulation of the normal equations from them is ba_accumulate.cpp.
#include <algorithm>
#include <cmath>

#include "ba_internal.h"
#include "rsvio/interfaces/camera.h"

namespace rsvio {
namespace ba {

// true: every pair through the general projectRollingShutter() (the reference the global-shutter fast
// path is checked against; switch on to measure it).
constexpr bool kGeneralProjection = false;

void buildStructure(BundleAdjuster::Impl& m, KeyframeList& window, const BundleAdjustmentConfig& cfg,
                    const std::vector<ActivePoint*>* only) {
  reindex(window);
  m.window = &window;
  const int nk = static_cast<int>(window.size());
  const int kd = cfg.layout.kfDim();
  m.nkd = nk * kd;
  m.nc = cfg.layout.windowDim(nk);
  m.gl = cfg.layout.lineDelay() ? cfg.layout.globalOffset(nk) + cfg.layout.lineDelayIndex() : -1;
  if (only) {
    std::vector<ActivePoint*> copy = *only;  // `only` may be m.points itself (BundleAdjuster::points())
    m.points.swap(copy);
  } else {
    m.points.clear();
    for (auto& kf : window)
      for (ActivePoint& p : kf->points) m.points.push_back(&p);
  }
  m.obs_refs.clear();
  m.point_obs_begin.assign(m.points.size() + 1, 0);
  for (auto& pw : m.pairs) pw.obs.clear();
  m.pairs.resize(static_cast<size_t>(nk) * nk);
  for (int h = 0; h < nk; ++h)
    for (int t = 0; t < nk; ++t) {
      m.pairs[static_cast<size_t>(h) * nk + t].host = window[h].get();
      m.pairs[static_cast<size_t>(h) * nk + t].target = window[t].get();
    }
  for (size_t i = 0; i < m.points.size(); ++i) {
    ActivePoint& p = *m.points[i];
    m.point_obs_begin[i] = static_cast<int>(m.obs_refs.size());
    for (size_t j = 0; j < p.obs.size(); ++j) {
      const int ref = static_cast<int>(m.obs_refs.size());
      m.obs_refs.push_back({static_cast<int>(i), static_cast<int>(j)});
      m.pairs[static_cast<size_t>(p.host->index) * nk + p.obs[j].target->index].obs.push_back(ref);
    }
  }
  m.point_obs_begin[m.points.size()] = static_cast<int>(m.obs_refs.size());
  m.fixed.assign(static_cast<size_t>(m.nc), 0);
  for (int k = 0; k < nk; ++k) {
    uint8_t* f = m.fixed.data() + static_cast<size_t>(k) * kd;
    if (window[k]->gauge)
      for (int i = 0; i < 8; ++i) f[i] = 1;
    if (!cfg.estimate_affine) f[StateLayout::kAffine] = f[StateLayout::kAffine + 1] = 1;
  }
  if (m.gl >= 0 && (nk == 0 || window.back()->kf_id + 1 < cfg.line_delay_min_keyframes))
    m.fixed[static_cast<size_t>(m.gl)] = 1;
  // The yaw of T_Wm_Wf about gravity is unobservable (visual_inertial_factor.h): held.
  if (cfg.layout.inertial) m.fixed[static_cast<size_t>(cfg.layout.globalOffset(nk) + StateLayout::kGlobalRot + 2)] = 1;
  // Arena of per-point blocks: host + one per observation at most.
  for (Linearization* L : {&m.cur, &m.trial}) {
    L->obs.resize(m.obs_refs.size());
    L->Hpp.assign(m.points.size(), 0.0);
    L->bp.assign(m.points.size(), 0.0);
    L->hpl.assign(m.points.size(), 0.0);
    L->blk_begin.resize(m.points.size());
    L->blk_count.assign(m.points.size(), 0);
    int total = 0;
    for (size_t i = 0; i < m.points.size(); ++i) {
      L->blk_begin[i] = total;
      total += 1 + (m.point_obs_begin[i + 1] - m.point_obs_begin[i]);
    }
    L->blk_ids.resize(static_cast<size_t>(total));
    L->hpc.resize(static_cast<size_t>(total) * kd);
  }
  m.chunks.resize(kPointChunks);
  for (ChunkSums& c : m.chunks) {  // points couple to the photometric blocks (and the line delay)
    c.H.resize(m.nkd, m.nkd);
    c.b.resize(m.nkd);
    c.Hl.resize(m.nkd);
  }
}

namespace {

// [I, -[p]x] (rs_projection.cpp's dLeftAction).
Eigen::Matrix<double, 3, 6> dLeftAction(const Vec3& p) {
  Eigen::Matrix<double, 3, 6> J;
  J.leftCols<3>().setIdentity();
  J.rightCols<3>() = -SO3d::hat(p);
  return J;
}

// Global shutter (no twists in the layout): projectRollingShutter() of host points at row time 0 with
// the same arithmetic in the same order, without the factors that are identities there (exp(0), its
// rotation matrix, the implicit-row correction with a = 0) and without filling its general outputs, so
// uv and the Jacobians are bit-identical to the general call. Fills valid, uv, d_uv_d_X, d_uv_d_T0 and
// d_uv_d_idepth of pw.proj; the host pose's Jacobian (accumulateChunkGlobal forms the host's blocks
// from the target's with the pair's adjoint), the twists' and the line delay's are not used by the
// global-shutter accumulation and are left as they are.
void projectPairGlobal(const CameraModel& camera, const RsFrame& host, const RsFrame& target, PairWork& pw) {
  const Eigen::Index n = pw.bearing.cols();
  pw.proj.resize(static_cast<size_t>(n));
  const SE3d T_w_h0 = host.T_c_w0.inverse();
  const Eigen::Matrix3d R_w_h0 = T_w_h0.rotationMatrix();
  const Eigen::Matrix3d R_t = target.T_c_w0.rotationMatrix();
  std::vector<int> idx;
  idx.reserve(static_cast<size_t>(n));
  Eigen::Matrix3Xd P0(3, n);
  Eigen::Matrix2Xd uv;
  std::vector<uint8_t> valid;
  std::vector<Jac23> J;
  Eigen::Index m = 0;
  for (Eigen::Index i = 0; i < n; ++i) {
    pw.proj[static_cast<size_t>(i)].valid = false;
    const double rho = pw.idepth[i];
    if (!(rho > 0.0) || !std::isfinite(rho)) continue;
    const Vec3 X = T_w_h0 * Vec3(pw.bearing.col(i) / rho);
    P0.col(m++) = target.T_c_w0 * X;
    idx.push_back(static_cast<int>(i));
  }
  P0.conservativeResize(3, m);
  camera.project(P0, uv, valid, &J);
  for (Eigen::Index k = 0; k < m; ++k) {
    const size_t i = static_cast<size_t>(idx[static_cast<size_t>(k)]);
    RsHostProjection& r = pw.proj[i];
    r.uv = uv.col(k);
    r.valid = valid[static_cast<size_t>(k)] != 0;
    if (!r.valid) continue;
    const Jac23& Jc = J[static_cast<size_t>(k)];
    r.d_uv_d_T0 = Jc * dLeftAction(P0.col(k));
    r.d_uv_d_X = Jc * R_t;
    const double rho = pw.idepth[static_cast<Eigen::Index>(i)];
    const Eigen::Matrix<double, 2, 3> d_uv_d_Z = r.d_uv_d_X * R_w_h0;
    r.d_uv_d_idepth = d_uv_d_Z * Vec3(-pw.bearing.col(static_cast<Eigen::Index>(i)) / (rho * rho));
  }
}

// Evaluates every observation of one host-target pair.
void evaluatePair(BundleAdjuster::Impl& m, PairWork& pw, Linearization& L, const BundleAdjustmentConfig& cfg,
                  const CameraModel& camera, const RowTiming& timing, const ResidualKernel& kernel) {
  const int n = static_cast<int>(pw.obs.size());
  if (n == 0) return;
  pw.bearing.resize(3, n);
  pw.v_h.resize(n);
  pw.idepth.resize(n);
  for (int k = 0; k < n; ++k) {
    const ObsRef& ref = m.obs_refs[static_cast<size_t>(pw.obs[static_cast<size_t>(k)])];
    const ActivePoint& p = *m.points[static_cast<size_t>(ref.point)];
    pw.bearing.col(k) = p.bearing;
    pw.v_h[k] = p.v;
    pw.idepth[k] = p.idepth;
  }
  const bool rolling = cfg.layout.rolling;
  RsFrame host{pw.host->state.T_c_w, rolling ? pw.host->state.twist : Vec6::Zero(),
               rolling ? pw.host->w_dot : Vec3::Zero()};
  RsFrame target{pw.target->state.T_c_w, rolling ? pw.target->state.twist : Vec6::Zero(),
                 rolling ? pw.target->w_dot : Vec3::Zero()};
  if (rolling) {
    pw.host_pts.resize(static_cast<size_t>(n));
    for (int k = 0; k < n; ++k)
      pw.host_pts[static_cast<size_t>(k)] =
          m.host_points[static_cast<size_t>(m.obs_refs[static_cast<size_t>(pw.obs[static_cast<size_t>(k)])].point)];
    projectRollingShutter(camera, timing, host, target, pw.bearing, pw.v_h, pw.idepth, pw.host_pts, pw.proj);
  } else if (kGeneralProjection) {
    projectRollingShutter(camera, timing, host, target, pw.bearing, pw.v_h, pw.idepth, pw.proj);
  } else {
    projectPairGlobal(camera, host, target, pw);
  }

  const ImageLevel& img = pw.target->pyramid->level(0);
  const double exposure_ratio = (pw.host->exposure_ms > 0.0 && pw.target->exposure_ms > 0.0)
                                    ? pw.target->exposure_ms / pw.host->exposure_ms
                                    : 1.0;
  const AffineTransfer tr = affineTransfer(pw.host->state.affine, pw.target->state.affine, exposure_ratio);
  const float alpha = static_cast<float>(tr.alpha), beta = static_cast<float>(tr.beta);
  const Eigen::Matrix3d R_w_h0 = pw.host->state.T_c_w.so3().inverse().matrix();
  const float e_out = kernel.outlier_energy;

  // Visit the observations in the order of their target rows (counting sort, stable): the pattern
  // samples then walk through the target image instead of jumping across its ~5 MB at random. Each
  // observation's result is written to its own slot, so the order changes no number.
  const int rows = img.height();
  std::vector<int> count(static_cast<size_t>(rows) + 2, 0), order(static_cast<size_t>(n));
  auto rowKey = [&](int k) {
    const RsHostProjection& pr = pw.proj[static_cast<size_t>(k)];
    const double y = pr.uv.y();
    if (!pr.valid || !(y >= 0.0) || !(y < rows)) return rows;  // invalid or outside: last
    return static_cast<int>(y);
  };
  for (int k = 0; k < n; ++k) ++count[static_cast<size_t>(rowKey(k)) + 1];
  for (int r = 0; r <= rows; ++r) count[static_cast<size_t>(r) + 1] += count[static_cast<size_t>(r)];
  for (int k = 0; k < n; ++k) order[static_cast<size_t>(count[static_cast<size_t>(rowKey(k))]++)] = k;

  PatternResidual res;
  for (int kk = 0; kk < n; ++kk) {
    const int k = order[static_cast<size_t>(kk)];
    const ObsRef& ref = m.obs_refs[static_cast<size_t>(pw.obs[static_cast<size_t>(k)])];
    const ActivePoint& p = *m.points[static_cast<size_t>(ref.point)];
    ObsLin& ol = L.obs[static_cast<size_t>(pw.obs[static_cast<size_t>(k)])];
    const RsHostProjection& pr = pw.proj[static_cast<size_t>(k)];
    ol.state = ObsState::kOob;
    ol.energy = e_out;
    if (!pr.valid) continue;
    // Local warp W = d p' / d p (host pixel -> target pixel at fixed inverse depth).
    Eigen::Matrix3d R_w_hp = R_w_h0;
    if (rolling) R_w_hp = R_w_h0 * pw.host_pts[static_cast<size_t>(k)].E;  // exp(-omega_h t_h)
    const Eigen::Matrix2d Wm = pr.d_uv_d_X * R_w_hp * p.d_bearing_d_uv * (1.0 / p.idepth);
    const float warp[4] = {static_cast<float>(Wm(0, 0)), static_cast<float>(Wm(0, 1)), static_cast<float>(Wm(1, 0)),
                           static_cast<float>(Wm(1, 1))};
    const float u = static_cast<float>(pr.uv.x()), v = static_cast<float>(pr.uv.y());
    ol.u = u;
    ol.v = v;
    if (!std::isfinite(u) || !std::isfinite(v) || !img.inside(u, v, 1.f)) continue;
    if (!evaluatePattern(img, u, v, warp, 1.f, p.pattern, alpha, beta, kernel, res)) continue;
    ol.grad_u = res.gx[kPatternCentre];
    ol.grad_v = res.gy[kPatternCentre];
    float sr = 0.f, sw = 0.f;
    for (int i = 0; i < kPatternSize; ++i) {
      sr += res.r[i];
      sw += res.w[i];
    }
    ol.mean_r = sr / kPatternSize;
    ol.mean_w = sw / kPatternSize;
    if (res.outlier) {
      ol.state = ObsState::kOutlier;
      continue;
    }
    ol.state = ObsState::kIn;
    ol.energy = res.energy;
    // M = K^T W K, g = K^T W r with K rows (gx, gy, c, A, -c, -1), c = A (I_host - b_host), A = alpha:
    // formed from 14 weighted sums over the pattern (the last three columns repeat the third and a
    // constant), not from 8 outer products.
    const double hb = pw.host->state.affine.b;
    const double A = tr.alpha;
    double s_w = 0, s_c = 0, s_cc = 0, s_x = 0, s_y = 0, s_xx = 0, s_xy = 0, s_yy = 0, s_xc = 0, s_yc = 0;
    double r_x = 0, r_y = 0, r_c = 0, r_1 = 0;
    for (int i = 0; i < kPatternSize; ++i) {
      const double c = A * (p.pattern.color[i] - hb);
      const double w = res.w[i], gx = res.gx[i], gy = res.gy[i], wr = w * res.r[i];
      s_w += w;
      s_c += w * c;
      s_cc += w * c * c;
      s_x += w * gx;
      s_y += w * gy;
      s_xx += w * gx * gx;
      s_xy += w * gx * gy;
      s_yy += w * gy * gy;
      s_xc += w * gx * c;
      s_yc += w * gy * c;
      r_x += wr * gx;
      r_y += wr * gy;
      r_c += wr * c;
      r_1 += wr;
    }
    // Written entry by entry (symmetric): Eigen's comma initializer showed as 2 % of a rolling-shutter
    // run's profile; the values are the same bits.
    const double m6[6][6] = {{s_xx, s_xy, s_xc, A * s_x, -s_xc, -s_x},
                             {s_xy, s_yy, s_yc, A * s_y, -s_yc, -s_y},
                             {s_xc, s_yc, s_cc, A * s_c, -s_cc, -s_c},
                             {A * s_x, A * s_y, A * s_c, A * A * s_w, -A * s_c, -A * s_w},
                             {-s_xc, -s_yc, -s_cc, -A * s_c, s_cc, s_c},
                             {-s_x, -s_y, -s_c, -A * s_w, s_c, s_w}};
    for (int i = 0; i < 6; ++i)
      for (int j = 0; j < 6; ++j) ol.M(i, j) = m6[i][j];
    ol.g(0) = r_x;
    ol.g(1) = r_y;
    ol.g(2) = r_c;
    ol.g(3) = A * r_1;
    ol.g(4) = -r_c;
    ol.g(5) = -r_1;
    ol.Jg.block<2, 6>(0, kColTargetPose) = pr.d_uv_d_T0;
    ol.Jg.col(kColIdepth) = pr.d_uv_d_idepth;
    if (rolling) {
      ol.Jg.block<2, 6>(0, kColHostPose) = pr.d_uv_d_Th0;
      ol.Jg.block<2, 6>(0, kColHostTwist) = pr.d_uv_d_xi_h;
      ol.Jg.block<2, 6>(0, kColTargetTwist) = pr.d_uv_d_xi;
      if (m.gl >= 0) ol.Jl = pr.d_uv_d_line_delay;
    }  // global shutter: the target pose and inverse depth only (accumulateChunkGlobal)
  }
}

}  // namespace

void evaluatePhotometric(BundleAdjuster::Impl& m, Linearization& L, const BundleAdjustmentConfig& cfg,
                         const CameraModel& camera, const RowTiming& timing) {
  const ResidualKernel kernel(cfg.residual);
  // The line delay being estimated is the globals' (the given timing's otherwise).
  m.timing = timing;
  if (m.gl >= 0 && m.globals) m.timing.line_delay_s = m.globals->state.line_delay_s;
  if (cfg.layout.rolling) {
    const KeyframeList& window = *m.window;
    std::vector<TwistExp> ex;
    ex.reserve(window.size());
    for (const auto& kf : window) ex.emplace_back(kf->state.twist);
    m.host_points.resize(m.points.size());
    const int np = static_cast<int>(m.points.size());
    m.runner->run(kPointChunks, [&](int chunk) {
      const int begin = static_cast<int>(static_cast<long>(np) * chunk / kPointChunks);
      const int end = static_cast<int>(static_cast<long>(np) * (chunk + 1) / kPointChunks);
      for (int i = begin; i < end; ++i) {
        const ActivePoint& p = *m.points[static_cast<size_t>(i)];
        if (!(p.idepth > 0.0) || !std::isfinite(p.idepth)) continue;  // projectRollingShutter skips it
        const Keyframe& h = *p.host;
        m.host_points[static_cast<size_t>(i)] = rsHostPoint(ex[static_cast<size_t>(h.index)],
                                                            m.timing.rowTime(p.v), p.bearing, p.idepth, true, h.w_dot);
      }
    });
  }
  if (!cfg.layout.rolling || cfg.host_blocks_from_adjoint) {  // the host-pose map, from the states evaluated here
    L.pair_adj.resize(m.pairs.size());
    for (size_t i = 0; i < m.pairs.size(); ++i)
      L.pair_adj[i] = (m.pairs[i].target->state.T_c_w * m.pairs[i].host->state.T_c_w.inverse()).Adj();
  }
  m.runner->run(static_cast<int>(m.pairs.size()),
                [&](int i) { evaluatePair(m, m.pairs[static_cast<size_t>(i)], L, cfg, camera, m.timing, kernel); });
}

void linearizePhotometric(BundleAdjuster::Impl& m, Linearization& L, const BundleAdjustmentConfig& cfg,
                          const CameraModel& camera, const RowTiming& timing, bool points_only) {
  evaluatePhotometric(m, L, cfg, camera, timing);
  accumulatePhotometric(m, L, cfg, points_only);
}

double keyframePriors(const Keyframe& kf, const BundleAdjustmentConfig& cfg, Eigen::Ref<Eigen::MatrixXd> H,
                      Eigen::Ref<Eigen::VectorXd> b) {
  double e = 0.0;
  const int ia = StateLayout::kAffine;
  if (cfg.estimate_affine && !kf.gauge) {
    const double a = kf.state.affine.a, bb = kf.state.affine.b;
    H(ia, ia) += cfg.affine_prior_a;
    b[ia] -= cfg.affine_prior_a * a;
    H(ia + 1, ia + 1) += cfg.affine_prior_b;
    b[ia + 1] -= cfg.affine_prior_b * bb;
    e += cfg.affine_prior_a * a * a + cfg.affine_prior_b * bb * bb;
  }
  if (cfg.layout.rolling) {
    const int it = StateLayout::kTwist;
    if (kf.has_twist_prior) {
      const Vec6 r = kf.state.twist - kf.twist_prior.mean;
      H.block<6, 6>(it, it) += kf.twist_prior.information;
      b.segment<6>(it) -= kf.twist_prior.information * r;
      e += r.dot(kf.twist_prior.information * r);
    } else {
      const Vec6 r = kf.state.twist - kf.twist_start;
      H.block<6, 6>(it, it).diagonal().array() += cfg.twist_regularization;
      b.segment<6>(it) -= cfg.twist_regularization * r;
      e += cfg.twist_regularization * r.squaredNorm();
    }
  }
  return e;
}

namespace {

double addCameraTermsTo(BundleAdjuster::Impl& m, const BundleAdjustmentConfig& cfg,
                        const std::vector<const WindowTerm*>& terms, Eigen::MatrixXd& H, Eigen::VectorXd& b) {
  const int kd = cfg.layout.kfDim();
  double e = 0.0;
  for (auto& kf : *m.window)
    e += keyframePriors(*kf, cfg, H.block(kf->index * kd, kf->index * kd, kd, kd), b.segment(kf->index * kd, kd));
  if (m.prior) e += m.prior->addTo(H, b);
  for (const WindowTerm* t : terms) e += t->linearize(*m.window, cfg.layout, H, b);
  return e;
}

}  // namespace

void addCameraTerms(BundleAdjuster::Impl& m, Linearization& L, const BundleAdjustmentConfig& cfg,
                    const std::vector<const WindowTerm*>& terms) {
  L.energy_other = addCameraTermsTo(m, cfg, terms, L.Hcc, L.bc);
}

double cameraTermsEnergy(BundleAdjuster::Impl& m, const BundleAdjustmentConfig& cfg,
                         const std::vector<const WindowTerm*>& terms) {
  m.probe_H.setZero(m.nc, m.nc);
  m.probe_b.setZero(m.nc);
  return addCameraTermsTo(m, cfg, terms, m.probe_H, m.probe_b);
}

}  // namespace ba
}  // namespace rsvio
