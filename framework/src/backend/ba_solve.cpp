// Bundle adjustment, solving: damping, Schur complement of the inverse depths or the full sparse system,
// back-substitution and the Levenberg-Marquardt loop (contract in rsvio/backend/bundle_adjustment.h).
#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <utility>

#include "ba_internal.h"
#include "rsvio/core/error.h"
#include "rsvio/interfaces/solver.h"

namespace rsvio {
namespace ba {

namespace {

constexpr double kMinHpp = 1e-8;      // a point with less inverse-depth information is not moved
constexpr double kMinDiag = 1e-12;    // a camera dimension with less information is held fixed

// Damped, masked camera block: H_ii (1 + lambda); fixed or unobserved dimensions get a unit row.
void dampAndMask(const BundleAdjuster::Impl& m, const Linearization& L, double lambda, Eigen::MatrixXd& H,
                 Eigen::VectorXd& b, std::vector<double>& keep) {
  H = L.Hcc;
  b = L.bc;
  keep.assign(static_cast<size_t>(m.nc), 1.0);
  for (int i = 0; i < m.nc; ++i) {
    if (m.fixed[static_cast<size_t>(i)] || !(H(i, i) > kMinDiag)) keep[static_cast<size_t>(i)] = 0.0;
  }
  for (int i = 0; i < m.nc; ++i) {
    if (keep[static_cast<size_t>(i)] == 0.0) {
      H.row(i).setZero();
      H.col(i).setZero();
      H(i, i) = 1.0;
      b[i] = 0.0;
    } else {
      H(i, i) *= 1.0 + lambda;
    }
  }
}

// H, b minus the chunks' Schur sums (photometric blocks and the line delay's row). kd: the keyframe
// block size the chunks were made with; for the rolling shutter's 14 they hold the diagonal and upper
// keyframe blocks only (schurChunk<14>), and H's lower blocks are mirrored from its upper ones after.
void subtractSchur(const BundleAdjuster::Impl& m, int kd, Eigen::MatrixXd& H, Eigen::VectorXd& b) {
  for (const ChunkSums& c : m.chunks) {
    H.topLeftCorner(m.nkd, m.nkd) -= c.H;
    b.head(m.nkd) -= c.b;
    if (m.gl >= 0) {
      H.col(m.gl).head(m.nkd) -= c.Hl;
      H.row(m.gl).head(m.nkd) -= c.Hl.transpose();
      H(m.gl, m.gl) -= c.Hll;
      b[m.gl] -= c.bl;
    }
  }
  if (kd == 14)
    for (int j = 0; j < m.nkd / kd; ++j)
      for (int i = j + 1; i < m.nkd / kd; ++i) H.block(i * kd, j * kd, kd, kd) = H.block(j * kd, i * kd, kd, kd).transpose();
}

template <int KD>
void schurChunk(BundleAdjuster::Impl& m, const Linearization& L, double lambda, const std::vector<double>& keep,
                int chunk) {
  ChunkSums& cs = m.chunks[static_cast<size_t>(chunk)];
  cs.H.setZero();
  cs.b.setZero();
  cs.Hl.setZero();
  cs.Hll = cs.bl = 0.0;
  const int np = static_cast<int>(m.points.size());
  const int begin = static_cast<int>(static_cast<long>(np) * chunk / kPointChunks);
  const int end = static_cast<int>(static_cast<long>(np) * (chunk + 1) / kPointChunks);
  const double keep_l = m.gl >= 0 ? keep[static_cast<size_t>(m.gl)] : 0.0;
  using V = Eigen::Matrix<double, KD, 1>;
  V hm[64];
  for (int i = begin; i < end; ++i) {
    const double Hpp = L.Hpp[static_cast<size_t>(i)] * (1.0 + lambda);
    if (!(Hpp > kMinHpp)) continue;
    const double inv = 1.0 / Hpp;
    const int ab = L.blk_begin[static_cast<size_t>(i)];
    const int nb = std::min(L.blk_count[static_cast<size_t>(i)], 64);
    for (int a = 0; a < nb; ++a) {
      const int ia = L.blk_ids[static_cast<size_t>(ab + a)];
      hm[a] = Eigen::Map<const V>(L.hpc.data() + static_cast<size_t>(ab + a) * KD)
                  .cwiseProduct(Eigen::Map<const V>(keep.data() + static_cast<size_t>(ia) * KD));
    }
    const double bp = L.bp[static_cast<size_t>(i)];
    for (int a = 0; a < nb; ++a) {
      const int ia = L.blk_ids[static_cast<size_t>(ab + a)];
      cs.b.template segment<KD>(ia * KD) += hm[a] * (bp * inv);
      for (int c = 0; c < nb; ++c) {
        const int ic = L.blk_ids[static_cast<size_t>(ab + c)];
        // Rolling shutter: diagonal and upper blocks only, the lower ones mirrored in subtractSchur.
        if (KD == 14 && ic < ia) continue;
        cs.H.template block<KD, KD>(ia * KD, ic * KD).noalias() += (hm[a] * inv) * hm[c].transpose();
      }
    }
    if (m.gl >= 0) {  // the line delay's row of the point's Schur complement
      const double hl = L.hpl[static_cast<size_t>(i)] * keep_l;
      for (int a = 0; a < nb; ++a) {
        const int ia = L.blk_ids[static_cast<size_t>(ab + a)];
        cs.Hl.template segment<KD>(ia * KD) += hm[a] * (hl * inv);
      }
      cs.Hll += hl * hl * inv;
      cs.bl += hl * bp * inv;
    }
  }
}

// dx_p from dx_c: rho step = (b_p - h^T dx_c) / H_pp.
void backSubstitute(const BundleAdjuster::Impl& m, const Linearization& L, double lambda, int kd,
                    const std::vector<double>& keep, const Eigen::VectorXd& dx_c, Eigen::VectorXd& dx_p) {
  dx_p.setZero(static_cast<Eigen::Index>(m.points.size()));
  for (size_t i = 0; i < m.points.size(); ++i) {
    const double Hpp = L.Hpp[i] * (1.0 + lambda);
    if (!(Hpp > kMinHpp)) continue;
    double r = L.bp[i];
    if (m.gl >= 0) r -= L.hpl[i] * keep[static_cast<size_t>(m.gl)] * dx_c[m.gl];
    const int ab = L.blk_begin[i];
    for (int a = 0; a < L.blk_count[i]; ++a) {
      const int ia = L.blk_ids[static_cast<size_t>(ab + a)];
      for (int k = 0; k < kd; ++k)
        r -= L.hpc[static_cast<size_t>(ab + a) * kd + k] * keep[static_cast<size_t>(ia * kd + k)] * dx_c[ia * kd + k];
    }
    dx_p[static_cast<Eigen::Index>(i)] = r / Hpp;
  }
}

bool solveSchur(BundleAdjuster::Impl& m, const Linearization& L, const BundleAdjustmentConfig& cfg,
                SolverBackend& solver, double lambda, Eigen::VectorXd& dx_c, Eigen::VectorXd& dx_p,
                std::string* message) {
  Eigen::MatrixXd H;
  Eigen::VectorXd b;
  std::vector<double> keep;
  dampAndMask(m, L, lambda, H, b, keep);
  if (cfg.layout.rolling) {
    m.runner->run(kPointChunks, [&](int c) { schurChunk<14>(m, L, lambda, keep, c); });
  } else {
    m.runner->run(kPointChunks, [&](int c) { schurChunk<8>(m, L, lambda, keep, c); });
  }
  subtractSchur(m, cfg.layout.kfDim(), H, b);
  // Jacobi scaling: the inertial blocks bring information up to ~1e11 (a gyro bias over 0.1 s) beside
  // twists with ~1e-6; solving D H D y = D b, dx = D y (D = diag(H)^-1/2) is the same step in exact
  // arithmetic and keeps the dense factorisation accurate.
  // The line delay (s per row, information ~1e12) needs it as much. Visual-inertial layouts and an
  // estimated line delay only (visual odometry keeps its unscaled, bit-identical steps).
  Eigen::VectorXd D = Eigen::VectorXd::Ones(H.rows());
  if (cfg.layout.inertial || m.gl >= 0)
    for (Eigen::Index i = 0; i < D.size(); ++i) D[i] = H(i, i) > 0.0 ? 1.0 / std::sqrt(H(i, i)) : 1.0;
  H = D.asDiagonal() * H * D.asDiagonal();
  b = D.cwiseProduct(b);
  SolverStats st;
  if (!solver.solveDense(H, b, dx_c, &st)) {
    if (message) *message = st.message;
    return false;
  }
  dx_c = D.cwiseProduct(dx_c);
  backSubstitute(m, L, lambda, cfg.layout.kfDim(), keep, dx_c, dx_p);
  return true;
}

void fullSparse(const BundleAdjuster::Impl& m, const Linearization& L, int kd, double lambda,
                Eigen::SparseMatrix<double>& S, Eigen::VectorXd& rhs, std::vector<double>& keep) {
  Eigen::MatrixXd H;
  Eigen::VectorXd b;
  dampAndMask(m, L, lambda, H, b, keep);
  const int np = static_cast<int>(m.points.size());
  const int n = m.nc + np;
  std::vector<Eigen::Triplet<double>> trip;
  for (int j = 0; j < m.nc; ++j)
    for (int i = 0; i < m.nc; ++i)
      if (H(i, j) != 0.0) trip.emplace_back(i, j, H(i, j));
  rhs.setZero(n);
  rhs.head(m.nc) = b;
  for (int p = 0; p < np; ++p) {
    const int row = m.nc + p;
    const double Hpp = L.Hpp[static_cast<size_t>(p)] * (1.0 + lambda);
    if (!(Hpp > kMinHpp)) {
      trip.emplace_back(row, row, 1.0);
      continue;
    }
    trip.emplace_back(row, row, Hpp);
    rhs[row] = L.bp[static_cast<size_t>(p)];
    if (m.gl >= 0) {
      const double v = L.hpl[static_cast<size_t>(p)] * keep[static_cast<size_t>(m.gl)];
      if (v != 0.0) {
        trip.emplace_back(m.gl, row, v);
        trip.emplace_back(row, m.gl, v);
      }
    }
    const int ab = L.blk_begin[static_cast<size_t>(p)];
    for (int a = 0; a < L.blk_count[static_cast<size_t>(p)]; ++a) {
      const int ia = L.blk_ids[static_cast<size_t>(ab + a)];
      for (int k = 0; k < kd; ++k) {
        const double v = L.hpc[static_cast<size_t>(ab + a) * kd + k] * keep[static_cast<size_t>(ia * kd + k)];
        if (v == 0.0) continue;
        trip.emplace_back(ia * kd + k, row, v);
        trip.emplace_back(row, ia * kd + k, v);
      }
    }
  }
  S.resize(n, n);
  S.setFromTriplets(trip.begin(), trip.end());  // duplicates (none expected) would be summed
}

bool solveFull(BundleAdjuster::Impl& m, const Linearization& L, const BundleAdjustmentConfig& cfg,
               SolverBackend& solver, double lambda, Eigen::VectorXd& dx_c, Eigen::VectorXd& dx_p,
               std::string* message) {
  Eigen::SparseMatrix<double> S;
  Eigen::VectorXd rhs, x;
  std::vector<double> keep;
  fullSparse(m, L, cfg.layout.kfDim(), lambda, S, rhs, keep);
  // The same Jacobi scaling as solveSchur's, for the same layouts.
  const bool scale = cfg.layout.inertial || m.gl >= 0;
  Eigen::VectorXd D;
  if (scale) {
    D = S.diagonal();
    for (Eigen::Index i = 0; i < D.size(); ++i) D[i] = D[i] > 0.0 ? 1.0 / std::sqrt(D[i]) : 1.0;
    S = D.asDiagonal() * S * D.asDiagonal();
    rhs = D.cwiseProduct(rhs);
  }
  SolverStats st;
  if (!solver.solveSparse(S, rhs, x, &st)) {
    if (message) *message = st.message;
    return false;
  }
  if (scale) x = D.cwiseProduct(x);
  dx_c = x.head(m.nc);
  dx_p = x.tail(static_cast<Eigen::Index>(m.points.size()));
  return true;
}

// Removes the monocular scale direction from a camera step and re-derives the point steps from it
// (DSO's SOLVER_ORTHOGONALIZE_X). Scaling the world by s about its origin maps a keyframe's translation
// t to s t, its twist's linear part v to s v and every inverse depth rho to rho / s; the photometric
// energy is invariant, so the direction n (d/ds at s = 1: t, v in the left-perturbation coordinates,
// -rho) is a null direction of H. Gradient steps have no component along it, but the damping
// (H + lambda diag H) does give them one: without this projection the scale random-walks by a few
// per cent per keyframe.
void removeScaleDirection(const BundleAdjuster::Impl& m, const Linearization& L, const BundleAdjustmentConfig& cfg,
                          double lambda, Eigen::VectorXd& dx_c, Eigen::VectorXd& dx_p) {
  const int kd = cfg.layout.kfDim();
  std::vector<double> keep(static_cast<size_t>(m.nc), 1.0);
  for (int i = 0; i < m.nc; ++i)
    if (m.fixed[static_cast<size_t>(i)] || !(L.Hcc(i, i) > kMinDiag)) keep[static_cast<size_t>(i)] = 0.0;
  Eigen::VectorXd n = Eigen::VectorXd::Zero(m.nc);
  for (const auto& kf : *m.window) scaleDirection(kf->state, cfg.layout, n.segment(kf->index * kd, kd));
  // With the inertial state the null direction scales T_Wm_Wf inversely: sigma = log s moves by -1.
  if (cfg.layout.inertial) n[cfg.layout.globalOffset(static_cast<int>(m.window->size())) + StateLayout::kGlobalScale] = -1.0;
  for (int i = 0; i < m.nc; ++i) n[i] *= keep[static_cast<size_t>(i)];
  // Oblique projection: the scale is measured on the translations only (m), the removed component is
  // along the null direction n. With a rolling shutter the twist velocities are weakly observable;
  // measuring the scale on them too (orthogonal projection) forces every velocity change into a
  // compensating scaling of the translations.
  Eigen::VectorXd mv = n;
  if (cfg.layout.rolling)
    for (const auto& kf : *m.window) mv.segment<3>(kf->index * kd + StateLayout::kTwist).setZero();
  if (cfg.layout.inertial) mv.tail(m.nc - m.nkd).setZero();
  const double mn = mv.dot(n);
  if (!(mn > 0.0)) return;
  dx_c -= n * (mv.dot(dx_c) / mn);
  backSubstitute(m, L, lambda, kd, keep, dx_c, dx_p);
}

// Writes the observation states and diagnostics of a linearisation back to the window.
void writeBack(BundleAdjuster::Impl& m, const Linearization& L) {
  for (size_t r = 0; r < m.obs_refs.size(); ++r) {
    const ObsRef& ref = m.obs_refs[r];
    ActiveObservation& o = m.points[static_cast<size_t>(ref.point)]->obs[static_cast<size_t>(ref.obs)];
    const ObsLin& ol = L.obs[r];
    o.state = ol.state;
    o.energy = ol.energy;
    o.u = ol.u;
    o.v = ol.v;
    o.grad_u = ol.grad_u;
    o.grad_v = ol.grad_v;
    o.mean_residual = ol.mean_r;
    o.mean_weight = ol.mean_w;
  }
  for (size_t i = 0; i < m.points.size(); ++i) m.points[i]->idepth_hessian = L.Hpp[i];
}

void fillStats(const Linearization& L, BundleAdjustmentStats& s) {
  s.photometric_energy = L.energy_photo_in;
  s.num_in = L.num_in;
  s.num_oob = L.num_oob;
  s.num_outlier = L.num_outlier;
  s.num_obs = L.num_in + L.num_oob + L.num_outlier;
}

// The small-step test (BundleAdjustmentConfig::min_step_rad, min_step_idepth): DSO's test on the pose
// steps' RMS over the window, the rotation in rad and the translation times the points' mean inverse
// depth before the step (so both are angles whatever the monocular scale; pose step = tangent
// (upsilon; omega) of the left perturbation at StateLayout::photometricOffset(k)), and the points' RMS
// inverse-depth step relative to that mean.
bool stepIsSmall(const KeyframeList& window, const std::vector<double>& idepth_before, const Eigen::VectorXd& dx_c,
                 const Eigen::VectorXd& dx_p, const BundleAdjustmentConfig& cfg) {
  if (window.empty() || idepth_before.empty()) return false;
  double rot2 = 0.0, trans2 = 0.0;
  for (const auto& kf : window) {
    const auto d = dx_c.segment<6>(cfg.layout.photometricOffset(kf->index) + StateLayout::kPose);
    trans2 += d.head<3>().squaredNorm();
    rot2 += d.tail<3>().squaredNorm();
  }
  const double n = static_cast<double>(window.size());
  double mean_idepth = 0.0;
  for (double r : idepth_before) mean_idepth += std::abs(r);
  mean_idepth /= static_cast<double>(idepth_before.size());
  const double idepth_rms = std::sqrt(dx_p.squaredNorm() / static_cast<double>(dx_p.size()));
  return std::sqrt(rot2 / n) < cfg.min_step_rad && std::sqrt(trans2 / n) * mean_idepth < cfg.min_step_rad &&
         idepth_rms < cfg.min_step_idepth * mean_idepth;
}

}  // namespace

}  // namespace ba

BundleAdjuster::BundleAdjuster(const BundleAdjustmentConfig& config, const CameraModel& camera,
                               const RowTiming& timing, SolverBackend& solver)
    : config_(config), camera_(camera), timing_(timing), solver_(solver), impl_(new Impl) {
  impl_->runner = std::make_unique<BlockRunner>(std::clamp(config.threads, 1, 2));
}

BundleAdjuster::~BundleAdjuster() = default;

void BundleAdjuster::setConfig(const BundleAdjustmentConfig& config) {
  if (config.layout.rolling != config_.layout.rolling)
    throw Error("BundleAdjuster::setConfig: the shutter (rolling or global) cannot change");
  config_ = config;
}

void BundleAdjuster::setGlobals(GlobalStates* globals) { impl_->globals = globals; }

const std::vector<ActivePoint*>& BundleAdjuster::points() const { return impl_->points; }

double BundleAdjuster::linearize(KeyframeList& window, const MarginalizationPrior& prior) {
  Impl& m = *impl_;
  m.prior = &prior;
  ba::buildStructure(m, window, config_, nullptr);
  ba::linearizePhotometric(m, m.cur, config_, camera_, timing_);
  ba::addCameraTerms(m, m.cur, config_, terms_);
  return m.cur.total();
}

bool BundleAdjuster::solveStep(double lambda, bool full, Eigen::VectorXd* dx_c, Eigen::VectorXd* dx_p,
                               std::string* message) {
  Eigen::VectorXd c, p;
  const bool ok = full ? ba::solveFull(*impl_, impl_->cur, config_, solver_, lambda, c, p, message)
                       : ba::solveSchur(*impl_, impl_->cur, config_, solver_, lambda, c, p, message);
  if (dx_c) *dx_c = c;
  if (dx_p) *dx_p = p;
  return ok;
}

void BundleAdjuster::fullSystem(Eigen::MatrixXd* H, Eigen::VectorXd* b) const {
  Eigen::SparseMatrix<double> S;
  Eigen::VectorXd rhs;
  std::vector<double> keep;
  ba::fullSparse(*impl_, impl_->cur, config_.layout.kfDim(), 0.0, S, rhs, keep);
  if (H) *H = Eigen::MatrixXd(S);
  if (b) *b = rhs;
}

BundleAdjustmentStats BundleAdjuster::evaluate(KeyframeList& window, const MarginalizationPrior& prior) {
  BundleAdjustmentStats s;
  s.energy_initial = s.energy_final = linearize(window, prior);
  ba::writeBack(*impl_, impl_->cur);
  ba::fillStats(impl_->cur, s);
  return s;
}

BundleAdjustmentStats BundleAdjuster::optimize(KeyframeList& window, const MarginalizationPrior& prior,
                                               int max_iterations) {
  Impl& m = *impl_;
  BundleAdjustmentStats s;
  double e = linearize(window, prior);
  s.energy_initial = e;
  double lambda = config_.lambda_initial;
  const bool full = solver_.prefersFullSystem();
  std::vector<double> idepth_backup(m.points.size());
  Eigen::VectorXd dx_c, dx_p;
  const int kd = config_.layout.kfDim();
  int failures = 0;
  int rejected_in_row = 0;
  for (int it = 0; it < max_iterations; ++it) {
    std::string msg;
    const bool ok = full ? ba::solveFull(m, m.cur, config_, solver_, lambda, dx_c, dx_p, &msg)
                         : ba::solveSchur(m, m.cur, config_, solver_, lambda, dx_c, dx_p, &msg);
    if (!ok || !dx_c.allFinite() || !dx_p.allFinite()) {
      s.message = msg.empty() ? "non-finite step" : msg;
      lambda = std::max(lambda * 10.0, 1e-4);
      if (++failures > 3) {
        s.solver_failed = true;
        break;
      }
      continue;
    }
    if (config_.fix_scale_gauge) ba::removeScaleDirection(m, m.cur, config_, lambda, dx_c, dx_p);
    const int nk = static_cast<int>(window.size());
    for (auto& kf : window) {
      kf->backup = kf->state;
      if (config_.layout.inertial)
        applyStep(kf->state, gatherState(dx_c, kf->index, nk, config_.layout), config_.layout);
      else
        applyStep(kf->state, dx_c.segment(kf->index * kd, kd), config_.layout);
    }
    if (m.globals && config_.layout.globalDim() > 0) {
      m.globals->backup = m.globals->state;
      applyGlobalStep(m.globals->state, dx_c.segment(config_.layout.globalOffset(nk), config_.layout.globalDim()),
                      config_.layout);
    }
    for (size_t i = 0; i < m.points.size(); ++i) {
      ActivePoint& p = *m.points[i];
      idepth_backup[i] = p.idepth;
      p.idepth = std::max(p.idepth + dx_p[static_cast<Eigen::Index>(i)], 1e-6);
    }
    // The trial's energy first; its blocks only when the step is accepted (a rejected step's
    // accumulation would be thrown away). The energies are the same bits as the full linearisation's.
    ba::evaluatePhotometric(m, m.trial, config_, camera_, timing_);
    ++s.iterations;
    const double e_new = ba::photometricEnergy(m, m.trial) + ba::cameraTermsEnergy(m, config_, terms_);
    if (e_new < e || config_.accept_all_steps) {
      const bool small = config_.min_step_rad > 0.0 && ba::stepIsSmall(window, idepth_backup, dx_c, dx_p, config_);
      ba::accumulatePhotometric(m, m.trial, config_, false);
      ba::addCameraTerms(m, m.trial, config_, terms_);
      std::swap(m.cur, m.trial);
      ++s.accepted;
      rejected_in_row = 0;
      const double rel = (e - e_new) / std::max(e, 1e-300);
      e = e_new;
      lambda *= 0.5;
      if (small) {
        s.small_step = true;
        break;
      }
      if (rel < config_.step_threshold && !config_.accept_all_steps) break;
    } else {
      for (auto& kf : window) kf->state = kf->backup;
      if (m.globals && config_.layout.globalDim() > 0) m.globals->state = m.globals->backup;
      for (size_t i = 0; i < m.points.size(); ++i) m.points[i]->idepth = idepth_backup[i];
      lambda *= 4.0;
      ++s.rejected;
      if (config_.max_rejected_steps > 0 && ++rejected_in_row >= config_.max_rejected_steps) break;
    }
  }
  s.energy_final = e;
  s.lambda = lambda;
  ba::writeBack(m, m.cur);
  ba::fillStats(m.cur, s);
  return s;
}

void BundleAdjuster::optimizeDepths(KeyframeList& window, const std::vector<ActivePoint*>& points, int iterations) {
  Impl& m = *impl_;
  m.prior = nullptr;
  ba::buildStructure(m, window, config_, &points);
  const size_t np = m.points.size();
  auto pointEnergy = [&](const ba::Linearization& L, size_t i) {
    double e = 0.0;
    for (int r = m.point_obs_begin[i]; r < m.point_obs_begin[i + 1]; ++r) e += L.obs[static_cast<size_t>(r)].energy;
    return e;
  };
  ba::linearizePhotometric(m, m.cur, config_, camera_, timing_, true);
  std::vector<double> step(np, 0.0), energy(np), backup(np);
  for (size_t i = 0; i < np; ++i) {
    energy[i] = pointEnergy(m.cur, i);
    step[i] = m.cur.Hpp[i] > 1e-8 ? m.cur.bp[i] / m.cur.Hpp[i] : 0.0;
  }
  for (int it = 0; it < iterations; ++it) {
    for (size_t i = 0; i < np; ++i) {
      backup[i] = m.points[i]->idepth;
      m.points[i]->idepth = std::max(backup[i] + step[i], 1e-6);
    }
    ba::linearizePhotometric(m, m.trial, config_, camera_, timing_, true);
    for (size_t i = 0; i < np; ++i) {
      const double e = pointEnergy(m.trial, i);
      if (e < energy[i]) {
        energy[i] = e;
        step[i] = m.trial.Hpp[i] > 1e-8 ? m.trial.bp[i] / m.trial.Hpp[i] : 0.0;
        // Keep the accepted linearisation of this point in `cur`.
        for (int r = m.point_obs_begin[i]; r < m.point_obs_begin[i + 1]; ++r)
          m.cur.obs[static_cast<size_t>(r)] = m.trial.obs[static_cast<size_t>(r)];
        m.cur.Hpp[i] = m.trial.Hpp[i];
      } else {
        m.points[i]->idepth = backup[i];
        step[i] *= 0.5;
      }
    }
  }
  ba::writeBack(m, m.cur);
}

void BundleAdjuster::pointsTerm(const KeyframeList& window, const std::vector<ActivePoint*>& points, double weight,
                                std::vector<int>* blocks, Eigen::MatrixXd* H, Eigen::VectorXd* b) {
  Impl& m = *impl_;
  m.prior = nullptr;
  KeyframeList& w = const_cast<KeyframeList&>(window);  // reindexed only
  ba::buildStructure(m, w, config_, &points);
  ba::linearizePhotometric(m, m.cur, config_, camera_, timing_);
  ba::writeBack(m, m.cur);  // the final linearisation of these observations (diagnostics log)
  const int kd = config_.layout.kfDim();
  // Schur complement over the points (no damping), fixed dimensions zeroed.
  Eigen::MatrixXd Hf;
  Eigen::VectorXd bf;
  std::vector<double> keep(static_cast<size_t>(m.nc), 1.0);
  for (int i = 0; i < m.nc; ++i) keep[static_cast<size_t>(i)] = m.fixed[static_cast<size_t>(i)] ? 0.0 : 1.0;
  if (config_.layout.rolling) {
    m.runner->run(ba::kPointChunks, [&](int c) { ba::schurChunk<14>(m, m.cur, 0.0, keep, c); });
  } else {
    m.runner->run(ba::kPointChunks, [&](int c) { ba::schurChunk<8>(m, m.cur, 0.0, keep, c); });
  }
  Hf = m.cur.Hcc;
  bf = m.cur.bc;
  ba::subtractSchur(m, config_.layout.kfDim(), Hf, bf);
  for (int i = 0; i < m.nc; ++i) {
    if (keep[static_cast<size_t>(i)] != 0.0) continue;
    Hf.row(i).setZero();
    Hf.col(i).setZero();
    bf[i] = 0.0;
  }
  Hf *= weight;
  bf *= weight;
  std::vector<int> blk;
  for (int k = 0; k < static_cast<int>(window.size()); ++k)
    if (Hf.block(k * kd, 0, kd, m.nc).cwiseAbs().maxCoeff() > 0.0) blk.push_back(k);
  // Rows of the term: the blocks' photometric rows, then (line delay estimated) the global block, whose
  // only entry the points reach is the line delay.
  std::vector<Eigen::Index> rows;
  for (int k : blk)
    for (int r = 0; r < kd; ++r) rows.push_back(static_cast<Eigen::Index>(k) * kd + r);
  const int g = config_.layout.lineDelay() ? config_.layout.globalDim() : 0;
  const int g0 = config_.layout.globalOffset(static_cast<int>(window.size()));
  for (int r = 0; r < g; ++r) rows.push_back(g0 + r);
  const Eigen::Index n = static_cast<Eigen::Index>(rows.size());
  H->resize(n, n);
  b->resize(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    (*b)[i] = bf[rows[static_cast<size_t>(i)]];
    for (Eigen::Index j = 0; j < n; ++j) (*H)(i, j) = Hf(rows[static_cast<size_t>(i)], rows[static_cast<size_t>(j)]);
  }
  *blocks = blk;
}

void BundleAdjuster::keyframePriorTerm(const Keyframe& kf, Eigen::MatrixXd* H, Eigen::VectorXd* b) const {
  const int kd = config_.layout.kfDim();
  H->setZero(kd, kd);
  b->setZero(kd);
  ba::keyframePriors(kf, config_, *H, *b);
  for (int i = 0; i < kd; ++i) {
    const bool fixed = (kf.gauge && i < 8) ||
                       (!config_.estimate_affine && (i == StateLayout::kAffine || i == StateLayout::kAffine + 1));
    if (!fixed) continue;
    H->row(i).setZero();
    H->col(i).setZero();
    (*b)[i] = 0.0;
  }
}

}  // namespace rsvio
