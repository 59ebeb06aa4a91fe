// The inertial part of the estimator (contract in inertial_state.h).
#include "inertial_state.h"

#include <cmath>
#include <sstream>

#include "rsvio/core/median.h"
#include "rsvio/core/time.h"
#include "rsvio/imu/imu_factor.h"
#include "rsvio/imu/imu_frames.h"
#include "rsvio/imu/preintegration.h"
#include "rsvio/imu/twist_prior.h"

namespace rsvio {

namespace {
constexpr double kBufferS = 60.0;               // IMU history kept (initialisation and the window)
constexpr double kRepreintegrateOffsetS = 1e-3; // re-preintegrate when the offset moved further
}  // namespace

InertialState::InertialState(const InertialOptions& o, const SensorSetup& sensors, bool rolling,
                             double twist_sigma_trans_m_s, double twist_sigma_rot_rad_s, GlobalStates& globals)
    : o_(o),
      sensors_(sensors),
      rolling_(rolling),
      twist_sigma_t_(twist_sigma_trans_m_s),
      twist_sigma_r_(twist_sigma_rot_rad_s),
      T_cm_i_(cameraFromImu(sensors.camera.T_B_C)),
      buffer_(5'000'000),
      globals_(globals) {
  globals_.state.time_offset_s = sensors.camera.time_offset_s;
  InertialTermOptions to;
  to.imu_weight = o.imu_weight;
  to.twist_weight = o.twist_weight;
  to.gyro_bias_sigma_before_init_rad_s = o.gyro_bias_sigma_before_init_rad_s;
  to.twist_gyro_sigma_before_init_rad_s = o.twist_gyro_sigma_before_init_rad_s;
  if (twist_sigma_t_ > 0.0) to.twist_sigma_trans_m_s = twist_sigma_t_;
  if (twist_sigma_r_ > 0.0) to.twist_sigma_rot_rad_s = twist_sigma_r_;
  term_ = std::make_unique<InertialTerm>(to, T_cm_i_, &globals_);
}

std::unique_ptr<InertialState> InertialState::restarted(GlobalStates& globals) const {
  auto s = std::make_unique<InertialState>(o_, sensors_, rolling_, twist_sigma_t_, twist_sigma_r_, globals);
  s->buffer_ = buffer_;
  return s;
}

int64_t InertialState::offsetNs() const { return sToNs(globals_.state.time_offset_s); }

void InertialState::addImu(const ImuSample& s) {
  buffer_.add(s);
  buffer_.dropBefore(s.t_ns - sToNs(kBufferS));
}

std::shared_ptr<const ImuFactor> InertialState::makeFactor(const Keyframe& from, const Keyframe& to) const {
  const int64_t off = offsetNs();
  if (!(to.t_ns > from.t_ns) || !buffer_.covers(from.t_ns + off, to.t_ns + off)) return nullptr;
  ImuBias b;
  b.gyro = from.state.bias_gyro;
  b.accel = from.state.bias_accel;
  return std::make_shared<ImuFactor>(ImuPreintegration::fromBuffer(buffer_, from.t_ns, to.t_ns, sensors_.imu, b,
                                                                   globals_.state.time_offset_s));
}

void InertialState::linkTwistEnergy(Keyframe& kf) const {
  kf.twist_energy = false;
  if (!rolling_ || !(twist_sigma_t_ > 0.0) || !(twist_sigma_r_ > 0.0)) return;
  const int64_t t = kf.t_ns + offsetNs();
  if (!buffer_.covers(t, t)) return;
  kf.gyro_at_t = buffer_.interpolate(t).gyro_rad_s;
  kf.twist_energy = true;
}

void InertialState::relinkBeforeInit(KeyframeList& window) const {
  if (initialised_) return;
  for (auto& kf : window) {
    if (twistBeforeInit()) linkTwistEnergy(*kf);
    if (gyroBeforeInit() && kf->imu_term && kf->imu_prev)
      if (std::shared_ptr<const ImuFactor> f = makeFactor(*kf->imu_prev, *kf)) kf->imu_factor = f;
  }
}

std::string InertialState::onNewKeyframe(Keyframe& kf, Keyframe* newest) {
  kf.imu_term = false;
  kf.imu_prev = nullptr;
  kf.imu_factor.reset();
  if (!initialised_ && twistBeforeInit()) {
    // Before the initialisation, optionally: the twist energy's rotation rows (inertial_term.h), and
    // the gyroscope's rate as the twist's starting rotation.
    linkTwistEnergy(kf);
    if (kf.twist_energy) kf.state.twist.tail<3>() = imuTwistRotation(kf.gyro_at_t, kf.state.bias_gyro, T_cm_i_);
  }
  if (!newest) return "";
  if (!initialised_) {
    // Before the initialisation, optionally: the factor for its rotation alone (inertial_term.h).
    if (!gyroBeforeInit()) return "";
    if (std::shared_ptr<const ImuFactor> f = makeFactor(*newest, kf)) {
      kf.imu_prev = newest;
      kf.imu_factor = f;
      kf.imu_term = true;
    }
    return "";
  }
  // Start at the prediction of the newest keyframe's state, then link the factor at that bias.
  kf.state.bias_gyro = newest->state.bias_gyro;
  kf.state.bias_accel = newest->state.bias_accel;
  kf.state.v_wm = newest->state.v_wm;
  std::shared_ptr<const ImuFactor> f = makeFactor(*newest, kf);
  if (!f) {
    std::ostringstream os;
    os << "no IMU data between keyframes at " << nsToS(newest->t_ns) << " s and " << nsToS(kf.t_ns)
       << " s: the new keyframe has no IMU factor";
    linkTwistEnergy(kf);
    return os.str();
  }
  ImuState si = imuStateOf(visualInertialStateOf(*newest), globals_.state.T_wm_wf, T_cm_i_);
  si.bias = f->preintegration().biasLin();
  kf.state.v_wm = predictState(si, f->preintegration()).v_w;
  kf.imu_prev = newest;
  kf.imu_factor = f;
  kf.imu_term = true;
  linkTwistEnergy(kf);
  if (kf.twist_energy)  // the IMU's twist (eq. 32) is a better start than the visual guess
    kf.state.twist = imuTwistPrior(kf.gyro_at_t, kf.state.v_wm, kf.state.bias_gyro, kf.state.T_c_w,
                                   globals_.state.T_wm_wf, T_cm_i_);
  return "";
}

bool InertialState::tryInitialize(const std::vector<ViInitKeyframe>& keyframes, KeyframeList& window,
                                  BundleAdjuster& ba, DynamicMarginalization& prior) {
  if (!o_.enabled || initialised_ || window.empty()) return false;
  const int64_t off = offsetNs();
  std::vector<ViInitKeyframe> kfs;
  for (const ViInitKeyframe& k : keyframes)
    if (buffer_.covers(k.t_ns + off, k.t_ns + off)) kfs.push_back(k);
  // imu.init_time_offset_search_ms: before the initialisation the offset is what the keyframes' rotations
  // and the gyroscope agree on, searched around the starting one (calibration plus correction) at each
  // attempt; the gyroscope's rotations used before the initialisation (frame rotations, twists) and the
  // initialisation then see the IMU at the right time, and the online estimate starts there.
  // The window's terms before the initialisation then read the gyroscope again at the new offset
  // (relinkBeforeInit): the keyframes' rotations the next search sees are no longer pulled toward the
  // old one, so the searches converge on the offset the images give instead of stopping short of it.
  if (searchesOffset() && kfs.size() >= 3) {
    const double before = globals_.state.time_offset_s;
    globals_.state.time_offset_s = estimateTimeOffset(kfs, buffer_, sensors_.imu, T_cm_i_,
                                                      sensors_.camera.time_offset_s, 1e-3 * o_.init_time_offset_search_ms);
    if (globals_.state.time_offset_s != before) relinkBeforeInit(window);
  }
  if (static_cast<int>(kfs.size()) < o_.init_min_keyframes) {
    std::ostringstream os;
    os << "waiting for keyframes with IMU data: " << kfs.size() << " < imu.init_min_keyframes "
       << o_.init_min_keyframes;
    status_ = os.str();
    return false;
  }
  ViInitOptions vo;
  vo.min_keyframes = o_.init_min_keyframes;
  vo.min_duration_s = o_.init_min_duration_s;
  vo.min_accel_excitation_m_s2 = o_.init_min_accel_excitation_m_s2;
  vo.max_gravity_norm_error = o_.init_max_gravity_norm_error;
  vo.accel_bias_prior_sigma_m_s2 = o_.accel_bias_prior_sigma_m_s2;
  vo.min_interval_s = o_.init_min_interval_s;
  const ViInitResult r = initializeVisualInertial(kfs, buffer_, sensors_.imu, T_cm_i_, globals_.state.time_offset_s, vo);
  const int64_t t_newest = window.back()->t_ns;
  if (!r.success) {
    status_ = r.status;
    if (r.status.rfind("rejected", 0) == 0) noteRefusal(t_newest);
    return false;
  }
  if (r.bias.gyro.norm() > o_.init_max_gyro_bias_rad_s || r.bias.accel.norm() > o_.init_max_accel_bias_m_s2) {
    std::ostringstream os;
    os << "initialisation refused: biases |b_g| " << r.bias.gyro.norm() << " rad/s, |b_a| " << r.bias.accel.norm()
       << " m/s^2 above imu.init_max_gyro_bias_rad_s " << o_.init_max_gyro_bias_rad_s
       << " / imu.init_max_accel_bias_m_s2 " << o_.init_max_accel_bias_m_s2
       << " (the keyframe poses do not fit the IMU yet)";
    status_ = os.str();
    noteRefusal(t_newest);
    return false;
  }
  if (o_.init_max_imu_chi2 > 0.0 && !(r.imu_chi2_mean <= o_.init_max_imu_chi2)) {
    std::ostringstream os;
    os << "initialisation refused: mean whitened IMU factor energy " << r.imu_chi2_mean << " at its solution (scale "
       << r.T_wm_wf.scale() << ") above imu.init_max_imu_chi2 " << o_.init_max_imu_chi2
       << " (the keyframe poses do not fit the IMU yet)";
    status_ = os.str();
    noteRefusal(t_newest);
    return false;
  }
  globals_.state.T_wm_wf = r.T_wm_wf;
  // imu.init_scale_factor (experiments): the metric world scaled about its origin, velocities with it.
  globals_.state.T_wm_wf.setScale(r.T_wm_wf.scale() * o_.init_scale_factor);
  scale_init_ = globals_.state.T_wm_wf.scale();
  for (auto& kf : window) {
    kf->state.bias_gyro = r.bias.gyro;
    kf->state.bias_accel = r.bias.accel;
    for (size_t i = 0; i < kfs.size(); ++i)
      if (kfs[i].t_ns == kf->t_ns) kf->state.v_wm = o_.init_scale_factor * r.velocities_wm[i];
  }
  initialised_ = true;
  init_t_ns_ = window.back()->t_ns;
  for (size_t k = 0; k < window.size(); ++k) {
    Keyframe& kf = *window[k];
    kf.imu_term = false;
    kf.imu_prev = nullptr;
    kf.imu_factor.reset();
    if (k > 0) {
      std::shared_ptr<const ImuFactor> f = makeFactor(*window[k - 1], kf);
      if (f) {
        kf.imu_prev = window[k - 1].get();
        kf.imu_factor = f;
        kf.imu_term = true;
      }
    }
    linkTwistEnergy(kf);
  }
  BundleAdjustmentConfig cfg = ba.config();
  cfg.layout.inertial = true;
  cfg.layout.estimate_time_offset = o_.estimate_time_offset;
  ba.setConfig(cfg);
  ba.setGlobals(&globals_);
  prior.setGlobals(&globals_);
  prior.setLayout(cfg.layout);
  prior.start(scale_init_, nsToS(init_t_ns_));
  for (auto& kf : window)
    if (kf->in_prior) {  // the prior has no information on these yet: any linearisation point is exact
      kf->lin.v_wm = kf->state.v_wm;
      kf->lin.bias_gyro = kf->state.bias_gyro;
      kf->lin.bias_accel = kf->state.bias_accel;
    }
  std::ostringstream os;
  os << "initialised: scale " << scale_init_ << " m per unit, gravity aligned, b_g |" << r.bias.gyro.norm()
     << "| rad/s, b_a |" << r.bias.accel.norm() << "| m/s^2, " << kfs.size() << " keyframes over " << r.duration_s
     << " s";
  status_ = os.str();
  return true;
}

void InertialState::noteRefusal(int64_t t_ns) {
  if (refusals_++ > 0) return;
  first_refusal_ = status_;
  first_refusal_t_ns_ = t_ns;
}

void InertialState::marginalizeTerms(Keyframe& leaving, const KeyframeList& window, DynamicMarginalization& prior) const {
  if (!initialised_ && !termsBeforeInit()) return;
  const StateLayout layout = prior.layout();
  std::vector<Keyframe*> kfs;
  Eigen::MatrixXd H;
  Eigen::VectorXd b;
  term_->linearizeInvolving(leaving, window, layout, &kfs, &H, &b);
  if (!kfs.empty()) {
    // Fixed dimensions must be zero in the prior's terms (marginalization.h): the gauge keyframe's pose
    // and affine, and (after the initialisation) the yaw of T_Wm_Wf.
    const int d = layout.stateDim();
    std::vector<Eigen::Index> zero;
    for (size_t i = 0; i < kfs.size(); ++i)
      if (kfs[i]->gauge)
        for (int r = 0; r < 8; ++r) zero.push_back(static_cast<Eigen::Index>(i) * d + r);
    if (initialised_) zero.push_back(static_cast<Eigen::Index>(kfs.size()) * d + StateLayout::kGlobalRot + 2);
    for (Eigen::Index z : zero) {
      H.row(z).setZero();
      H.col(z).setZero();
      b[z] = 0.0;
    }
    if (initialised_)
      prior.addScaleTerm(kfs, H, b, true);  // IMU factors and the twist energy depend on the scale
    else
      prior.addTerm(kfs, H, b);  // the gyroscope's rotations alone: on the poses, scale-free
  }
  leaving.imu_term = false;
  leaving.twist_energy = false;
  leaving.imu_prev = nullptr;
  leaving.imu_factor.reset();
  for (const auto& w : window)
    if (w->imu_prev == &leaving) {
      w->imu_term = false;
      w->imu_prev = nullptr;
      w->imu_factor.reset();
    }
}

void InertialState::refreshFactors(KeyframeList& window) {
  if (!initialised_) return;
  for (auto& kf : window) {
    if (!kf->imu_term || !kf->imu_prev || !kf->imu_factor) continue;
    const ImuPreintegration& p = kf->imu_factor->preintegration();
    const Keyframe& i = *kf->imu_prev;
    const bool moved = (i.state.bias_gyro - p.biasLin().gyro).norm() > o_.repreintegrate_gyro_bias_rad_s ||
                       (i.state.bias_accel - p.biasLin().accel).norm() > o_.repreintegrate_accel_bias_m_s2 ||
                       std::abs(globals_.state.time_offset_s - p.timeOffsetLin()) > kRepreintegrateOffsetS;
    if (!moved) continue;
    std::shared_ptr<const ImuFactor> f = makeFactor(i, *kf);
    if (f) kf->imu_factor = f;
  }
}

std::string InertialState::checkDivergence(const KeyframeList& window) {
  if (!initialised_) return "";
  std::ostringstream os;
  const double s = scale();
  if (!std::isfinite(s) || s > scale_init_ * o_.fail_max_scale_change || s < scale_init_ / o_.fail_max_scale_change) {
    os << "scale collapse: scale " << s << " against " << scale_init_
       << " at the visual-inertial initialisation (imu.fail_max_scale_change " << o_.fail_max_scale_change << ")";
    return os.str();
  }
  double chi2 = 0.0;
  int n = 0;
  for (const auto& kf : window) {
    const double bg = kf->state.bias_gyro.norm(), ba = kf->state.bias_accel.norm();
    if (!std::isfinite(bg) || bg > o_.fail_max_gyro_bias_rad_s) {
      os << "gyroscope bias runaway: |b_g| " << bg << " rad/s at keyframe " << kf->kf_id
         << " > imu.fail_max_gyro_bias_rad_s " << o_.fail_max_gyro_bias_rad_s;
      return os.str();
    }
    if (!std::isfinite(ba) || ba > o_.fail_max_accel_bias_m_s2) {
      os << "accelerometer bias runaway: |b_a| " << ba << " m/s^2 at keyframe " << kf->kf_id
         << " > imu.fail_max_accel_bias_m_s2 " << o_.fail_max_accel_bias_m_s2;
      return os.str();
    }
    double e = 0.0;
    if (term_->imuResidual(*kf, nullptr, &e)) {
      chi2 += e;
      ++n;
    }
  }
  const bool settled = !window.empty() && nsToS(window.back()->t_ns - init_t_ns_) >= o_.fail_grace_s;
  if (n > 0 && (!std::isfinite(chi2) || (settled && !(chi2 / n <= o_.fail_max_imu_chi2)))) {
    os << "exploding IMU residuals: mean whitened energy " << chi2 / n << " per factor > imu.fail_max_imu_chi2 "
       << o_.fail_max_imu_chi2;
    return os.str();
  }
  if (!settled || n == 0) return "";
  // Sustained: the run's level is the median of its first fail_sustained_s after the grace; after it,
  // every optimisation since high_chi2_since_ns_ had a mean above max(limit, factor x level).
  const int64_t t_ns = window.back()->t_ns;
  const double mean = chi2 / n;
  energies_.emplace_back(t_ns, mean);
  if (!(o_.fail_sustained_imu_chi2 > 0.0)) return "";
  if (energy_level_ < 0.0) {
    if (nsToS(t_ns - energies_.front().first) < o_.fail_sustained_s) return "";
    std::vector<double> v;
    for (const auto& e : energies_) v.push_back(e.second);
    v.pop_back();  // the level is of the span before this optimisation
    energy_level_ = v.empty() ? mean : upperMedian(v);
  }
  const double limit = std::max(o_.fail_sustained_imu_chi2, o_.fail_sustained_factor * energy_level_);
  if (!(mean > limit)) {
    high_chi2_since_ns_ = -1;
    return "";
  }
  if (high_chi2_since_ns_ < 0) high_chi2_since_ns_ = t_ns;
  if (nsToS(t_ns - high_chi2_since_ns_) >= o_.fail_sustained_s) {
    os << "IMU residuals stay high: mean whitened energy per factor above " << limit << " for "
       << nsToS(t_ns - high_chi2_since_ns_) << " s (now " << mean << "; the run's level " << energy_level_
       << "; imu.fail_sustained_imu_chi2 " << o_.fail_sustained_imu_chi2 << ", imu.fail_sustained_factor "
       << o_.fail_sustained_factor << ", imu.fail_sustained_s " << o_.fail_sustained_s
       << "): the window broke and no longer fits the IMU";
    return os.str();
  }
  return "";
}

std::string InertialState::residualWarning() const {
  if (!(o_.warn_imu_chi2 > 0.0) || energies_.empty()) return "";
  std::vector<double> v;
  for (const auto& e : energies_) v.push_back(e.second);
  const double median = upperMedian(v);
  if (!(median > o_.warn_imu_chi2)) return "";
  std::ostringstream os;
  os << "the window's IMU residuals stayed high: median whitened energy " << median << " per factor over "
     << energies_.size() << " optimisations after the initialisation (a consistent factor has about 15; "
     << "imu.warn_imu_chi2 " << o_.warn_imu_chi2
     << "): the trajectory the images give does not fit the IMU; the model lacks an effect (a rolling shutter, a "
        "camera-IMU time offset, ...) or the IMU noise or calibration is wrong; rsvio diagnose on this run looks "
        "for the effect it lacks";
  return os.str();
}

void InertialState::fillMotionState(const Keyframe& ref, MotionState* ms) const {
  if (!initialised_) return;
  ms->has_inertial = true;
  ms->T_wm_wf = SE3d(globals_.state.T_wm_wf.so3(), Vec3::Zero());
  ms->scale = scale();
  ms->bias_gyro = ref.state.bias_gyro;
  ms->bias_accel = ref.state.bias_accel;
  ms->v_wm = ref.state.v_wm;
  const int64_t off = offsetNs();
  if (ms->t_ns <= ref.t_ns || !buffer_.covers(ref.t_ns + off, ms->t_ns + off)) return;
  const ImuState si = imuStateOf(visualInertialStateOf(ref), globals_.state.T_wm_wf, T_cm_i_);
  const ImuPreintegration pre = ImuPreintegration::fromBuffer(buffer_, ref.t_ns, ms->t_ns, sensors_.imu, si.bias,
                                                              globals_.state.time_offset_s);
  ms->v_wm = predictState(si, pre).v_w;
}

bool InertialState::frameTwist(const Keyframe& ref, int64_t t_ns, const SE3d& T_c_w, Vec6* xi) const {
  if (!rolling_ || !o_.frame_twist_from_imu) return false;
  if (!initialised_) {  // no scale, velocity or bias yet: eq. 25's rotation from the gyroscope alone
    Vec3 w;
    if (!o_.frame_rotation_from_gyro_before_init || !gyroRate(t_ns, ref.state.bias_gyro, &w)) return false;
    xi->tail<3>() = w;
    return true;
  }
  return imuFrameTwist(buffer_, sensors_.imu, imuStateOf(visualInertialStateOf(ref), globals_.state.T_wm_wf, T_cm_i_),
                       ref.t_ns, t_ns, globals_.state.time_offset_s, T_c_w, globals_.state.T_wm_wf, T_cm_i_, xi);
}

Vec3 InertialState::readoutWDot(int64_t t_ns) const {
  constexpr int64_t h = 10'000'000;  // 10 ms: two gyroscope samples at 200 Hz
  const int64_t t = t_ns + offsetNs();
  if (!rolling_ || !o_.readout_angular_acceleration || !buffer_.covers(t - h, t + h)) return Vec3::Zero();
  const Vec3 w_minus = imuTwistRotation(buffer_.interpolate(t - h).gyro_rad_s, Vec3::Zero(), T_cm_i_);
  const Vec3 w_plus = imuTwistRotation(buffer_.interpolate(t + h).gyro_rad_s, Vec3::Zero(), T_cm_i_);
  return (w_plus - w_minus) / (2e-9 * static_cast<double>(h));
}

bool InertialState::gyroRate(int64_t t_ns, const Vec3& bias_gyro, Vec3* w) const {
  const int64_t t = t_ns + offsetNs();
  if (!buffer_.covers(t, t)) return false;
  *w = imuTwistRotation(buffer_.interpolate(t).gyro_rad_s, bias_gyro, T_cm_i_);
  return true;
}

bool InertialState::gyroRotation(int64_t t0_ns, int64_t t1_ns, const Vec3& bias_gyro, SO3d* R_1_0) const {
  const int64_t off = offsetNs();
  if (t1_ns < t0_ns || !buffer_.covers(t0_ns + off, t1_ns + off)) return false;
  constexpr int64_t kStep = 5'000'000;
  const int64_t steps = std::max<int64_t>(1, (t1_ns - t0_ns + kStep - 1) / kStep);
  SO3d R;
  for (int64_t k = 0; k < steps; ++k) {
    const int64_t a = t0_ns + (t1_ns - t0_ns) * k / steps, b = t0_ns + (t1_ns - t0_ns) * (k + 1) / steps;
    Vec3 w;
    if (!gyroRate(a + (b - a) / 2, bias_gyro, &w)) return false;
    R = SO3d::exp(w * (1e-9 * static_cast<double>(b - a))) * R;
  }
  *R_1_0 = R;
  return true;
}

}  // namespace rsvio
