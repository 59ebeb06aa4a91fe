// The estimator behind `rsvio run` (contract in rsvio/system/odometry.h): set-up from the effective
// config, the per-frame loop (preprocess, track, trace candidates, keyframe decision), the monocular
// start's hand-over, a keyframe's steps in DSO's order, finish() and the results. The parts it
// composes are listed in odometry_impl.h.
#include <algorithm>
#include <cmath>
#include <sstream>

#include "odometry_impl.h"
#include "rsvio/backend/keyframe_policy.h"
#include "rsvio/config/validate.h"
#include "rsvio/core/error.h"
#include "rsvio/core/time.h"
#include "rsvio/imu/imu_frames.h"
#include "rsvio/imu/inertial_options.h"
#include "rsvio/plugin/host.h"

namespace rsvio {
namespace {

template <class I>
std::unique_ptr<I> makeSlot(PluginHost& host, const nlohmann::json& cfg, const std::string& path) {
  const nlohmann::json* node = &cfg;
  std::stringstream ss(path);
  std::string part;
  while (std::getline(ss, part, '.')) node = &node->at(part);
  return host.create<I>(node->at("plugin").get<std::string>(), slotParams(cfg, path), path);
}

}  // namespace

Odometry::Impl::Impl(const nlohmann::json& cfg, PluginHost& host, const SensorSetup& s) : config(cfg), sensors(s) {
  const InertialOptions io = inertialOptionsFromConfig(cfg);
  // The offset every part uses (t_imu = t_cam + offset): the calibration's plus imu.time_offset_correction_ms.
  sensors.camera.time_offset_s = io.assumedTimeOffsetS(s.camera);
  seed = static_cast<uint64_t>(cfg.value("seed", 0L));
  threads = std::clamp(static_cast<int>(cfg.value("threads", 1L)), 1, 2);
  for (const char* slot : {"camera", "shutter", "solver"})
    if (!cfg.contains(slot)) throw ConfigError(std::string(slot) + ": the effective config has no such slot");
  camera = makeSlot<CameraModel>(host, cfg, "camera");
  camera->setCalibration(sensors.camera);
  shutter = makeSlot<ShutterModel>(host, cfg, "shutter");
  shutter->setCalibration(sensors.camera);
  solver = makeSlot<SolverBackend>(host, cfg, "solver");
  if (cfg.contains("photometric") && cfg.at("photometric").is_object())
    for (auto it = cfg.at("photometric").begin(); it != cfg.at("photometric").end(); ++it) {
      if (it->is_null()) continue;
      photometric_keys.push_back("photometric." + it.key());
      photometric.push_back(makeSlot<PhotometricModel>(host, cfg, photometric_keys.back()));
      photometric.back()->setSensors(sensors);
      photometric_ptrs.push_back(photometric.back().get());
    }
  if (cfg.contains("motion") && cfg.at("motion").is_object())
    for (auto it = cfg.at("motion").begin(); it != cfg.at("motion").end(); ++it) {
      if (it->is_null()) continue;
      motion.push_back(makeSlot<MotionPrior>(host, cfg, "motion." + it.key()));
      motion.back()->setSensors(sensors);
    }
  // Sections with defaults filled (the run schema registers them; a config without them still runs).
  fo = frontendOptions(sectionParams(cfg, "frontend", frontendParamTable()), seed, threads);
  bo = backendOptionsFromConfig(cfg);

  timing = RowTiming::from(*shutter, *camera);
  rolling = shutter->isRolling();
  WindowSetup ws;
  BundleAdjustmentConfig& bc = ws.ba;
  for (const PhotometricModel* p : photometric_ptrs)
    if (p->hasAffineBrightness()) {
      estimate_affine = true;
      bc.affine_prior_a = p->affinePriorA();
      bc.affine_prior_b = p->affinePriorB();
    }
  bc.layout.rolling = rolling;
  bc.layout.estimate_line_delay = rolling && shutter->estimatesLineDelay();
  line_delay_start_s = timing.line_delay_s;
  bc.residual = fo.residual;
  bc.estimate_affine = estimate_affine;
  bc.lambda_initial = bo.lambda_initial;
  bc.step_threshold = bo.step_threshold;
  bc.max_rejected_steps = bo.max_rejected_steps;
  bc.accept_all_steps = bo.accept_all_steps;
  bc.host_blocks_from_adjoint = bo.host_blocks_from_adjoint;
  bc.min_step_rad = bo.min_step_rad;
  bc.min_step_idepth = bo.min_step_idepth;
  bc.twist_regularization = bo.twist_regularization;
  bc.line_delay_min_keyframes = bo.line_delay_hold_keyframes;
  bc.threads = threads;
  if (rolling)
    for (const auto& m : motion)
      if (m->smoothMotionInformation(&ws.smooth_motion_information)) {
        ws.smooth_motion = true;
        break;
      }
  ws.backend = bo;
  ws.frontend = fo;
  ws.seed = seed;
  ws.dynamic_marginalization.enabled = io.enabled && io.dynamic_marginalization;
  ws.dynamic_marginalization.interval = io.dynamic_marginalization_interval;

  window_setup = ws;
  tracker_options = fo.track;
  tracker_options.residual = fo.residual;
  tracker_options.estimate_a = tracker_options.estimate_b = estimate_affine;
  tracker_options.threads = threads;
  for (const auto& m : motion) motion_ptrs.push_back(m.get());
  record = std::make_unique<RunRecord>(*camera, timing, rolling, estimate_affine, sensors.camera);
  window = std::make_unique<KeyframeWindow>(window_setup, *camera, timing, *solver);
  if (io.enabled) {
    if (!sensors.has_imu)
      throw ConfigError("imu.enabled: the dataset " + sensors.dataset_dir +
                        " has no IMU (imu0/data.csv); use a visual-odometry config (gs_vo, rs_vo) or "
                        "--set imu.enabled=false");
    double sigma_t = 0.0, sigma_r = 0.0;  // the IMU twist energy's Sigma, from the motion prior that has one
    for (const auto& m : motion)
      if (m->twistEnergySigma(&sigma_t, &sigma_r)) break;
    inertial = std::make_unique<InertialState>(io, sensors, rolling, sigma_t, sigma_r, window->globals());
    record->setProvisional(io.init_restart_refusals > 0 && io.init_max_restarts > 0);
  } else if (sensors.has_imu) {
    record->addWarning("the dataset has an IMU; this estimator runs pure visual odometry (IMU ignored)");
  }
  makeParts();
  // Models estimated online by alternation (photometric.vignette without a calibration) get the rows
  // of what leaves the window (refinePhotometric). Any other model's own parameters
  // (PhotometricModel::numParams, e.g. photometric.response's gamma in mode "estimate") are not
  // optimised by this back end: say so instead of running silently as if the model were there.
  for (size_t i = 0; i < photometric_ptrs.size(); ++i)
    if (photometric_ptrs[i]->estimatesOnline()) photometric_online.push_back(i);
  record->keepRowsForPhotometric(!photometric_online.empty());
  for (size_t i = 0; i < photometric_ptrs.size(); ++i)
    if (const int n = photometric_ptrs[i]->numParams(); n > 0 && !photometric_ptrs[i]->estimatesOnline())
      record->addWarning(photometric_keys[i] + ": its " + std::to_string(n) +
                         " parameter(s) are not estimated by the back end; the model leaves the images as "
                         "they are (a calibrated mode applies it)");
}

void Odometry::Impl::makeParts() {
  tracking = std::make_unique<Tracking>(tracker_options, *camera, timing, motion_ptrs);
  start = std::make_unique<MonoStart>(bo, *camera, timing);
  if (!inertial) return;
  window->setInertial(inertial.get());
  record->setGlobals(&window->globals());
  const InertialState* in = inertial.get();
  if (rolling && in->options().init_rates_from_gyro && !in->searchesOffset())  // see InertialOptions
    start->setRateSource([in](int64_t t_ns, Vec3* w) { return in->gyroRate(t_ns, Vec3::Zero(), w); });
  if (in->options().init_track_guess_from_gyro)
    start->setTrackGuessSource(
        [in](int64_t t0_ns, int64_t t1_ns, SO3d* R) { return in->gyroRotation(t0_ns, t1_ns, Vec3::Zero(), R); });
}

bool Odometry::Impl::canRestart(int64_t t_ns) const {
  if (!inertial || inertial->initialised()) return false;
  const InertialOptions& o = inertial->options();
  return o.init_restart_refusals > 0 && static_cast<int>(restarts.size()) < o.init_max_restarts &&
         attempt_t0_ns >= 0 && nsToS(t_ns - attempt_t0_ns) <= o.init_restart_within_s;
}

// Restart (InertialOptions::init_restart_refusals): the attempt's keyframes, points and rows are
// dropped and its frames become untracked (RunRecord::restart); the window (with its global states),
// the tracking and the monocular start are made afresh, the line delay back at its start value, and
// the inertial state starts again with the IMU buffer it has. The next frame begins a new start.
void Odometry::Impl::restart(int64_t frame_index, int64_t t_ns, const std::string& why) {
  std::ostringstream os;
  os << "the start was discarded at frame " << frame_index << " (t " << io::formatSeconds(t_ns)
     << " s) and begun again from the next frame: " << why;
  record->addWarning(os.str());
  restarts.push_back({{"frame", frame_index}, {"t_s", nsToS(t_ns)}, {"reason", why}});
  record->restart();
  timing.line_delay_s = line_delay_start_s;
  auto w = std::make_unique<KeyframeWindow>(window_setup, *camera, timing, *solver);
  auto in = inertial->restarted(w->globals());
  window = std::move(w);
  inertial = std::move(in);
  makeParts();
  initialized = false;
  failed = false;
  failure.clear();
  vi_init_t_ns = -1;
  poorly_explained_frames = 0;
  first_poorly_explained = -1;
  attempt_first_frame = -1;  // the next frame's
  attempt_t0_ns = -1;
  record->setProvisional(static_cast<int>(restarts.size()) < inertial->options().init_max_restarts);
}

// Visual-inertial: the initialisation at each new keyframe until it succeeds, on the keyframe poses of
// the run so far (the last 30 keyframes; marginalised ones at their final state).
void Odometry::Impl::tryInertialInitialisation() {
  if (!inertial || inertial->initialised() || window->size() < 2) return;
  std::map<int64_t, SE3d> by_time;
  for (const auto& [id, r] : record->keyframeRecords()) by_time[r.t_ns] = r.state.T_c_w;
  for (const auto& k : window->keyframes()) by_time[k->t_ns] = k->state.T_c_w;
  std::vector<ViInitKeyframe> kfs;
  for (const auto& [t, T] : by_time) kfs.push_back(ViInitKeyframe{t, T});
  constexpr size_t kMaxInitKeyframes = 30;
  if (kfs.size() > kMaxInitKeyframes) kfs.erase(kfs.begin(), kfs.end() - kMaxInitKeyframes);
  if (window->initializeInertial(kfs)) {
    vi_init_t_ns = window->newest().t_ns;
    record->setMetric(window->newest().t_ns);
  }
}

// A new keyframe's inertial terms (InertialState::onNewKeyframe) and the weights of its smooth-motion
// prior where the IMU measures its twist: the whole twist after the initialisation
// (imu.smooth_motion_weight), the rotation alone before it (imu.smooth_motion_rot_weight_before_init).
void Odometry::Impl::linkInertial(Keyframe& kf) {
  kf.w_dot = inertial->readoutWDot(kf.t_ns);
  const std::string w = inertial->onNewKeyframe(kf, window->empty() ? nullptr : &window->newest());
  if (!w.empty()) record->addWarning(w);
  if (!kf.twist_energy) return;
  if (inertial->initialised())
    kf.motion_weight = inertial->options().smooth_motion_weight;
  else
    kf.motion_weight_rot = inertial->options().smooth_motion_rot_weight_before_init;
}

void Odometry::Impl::fillInertial(int64_t t_ns) {
  if (!inertial || !inertial->initialised() || window->empty()) return;
  if (MotionState* ms = tracking->historyAt(t_ns)) inertial->fillMotionState(window->newest(), ms);
}

io::Trajectory Odometry::Impl::toBody(io::Trajectory t, const std::vector<RxSO3d>& T_wm_wf) const {
  if (!inertial || !inertial->initialised() || T_wm_wf.size() != t.poses.size()) return t;
  t.frame = io::PoseFrame::kBody;
  // Stamps on the IMU clock: t_imu = t_cam + time offset (the final estimate when it is estimated).
  const int64_t offset_ns = sToNs(inertial->timeOffset());
  for (size_t i = 0; i < t.poses.size(); ++i) {
    io::StampedPose& p = t.poses[i];
    p.t_ns += offset_ns;
    const SE3d T_c_w = SE3d(p.q_W_X, p.p_W_X).inverse();
    const SE3d T_wm_b = imuPoseFromCamera(T_c_w, T_wm_wf[i], inertial->T_cm_i());
    p.p_W_X = T_wm_b.translation();
    p.q_W_X = T_wm_b.unit_quaternion();
  }
  return t;
}

void Odometry::Impl::fail(const std::string& reason) {
  if (failed) return;
  failed = true;
  failure = reason;
}

FrameStatus Odometry::Impl::track(const Frame& frame, std::shared_ptr<const ImagePyramid> pyr) {
  const Keyframe& ref = window->newest();
  FrameRecord rec;
  rec.index = frame.index;
  rec.t_ns = frame.t_ns;
  rec.exposure_ms = frame.exposure_ms;
  TrackingFrame info;
  info.t_ns = frame.t_ns;
  info.exposure_ms = frame.exposure_ms;
  info.twist = rolling ? tracking->frameTwistGuess(&ref) : Vec6::Zero();
  // Only where InertialState::frameTwist has a twist to give: no motion-prior guesses made for nothing.
  const bool imu_twist = rolling && inertial && inertial->options().frame_twist_from_imu &&
                         (inertial->initialised() || inertial->options().frame_rotation_from_gyro_before_init);
  if (imu_twist) {  // the IMU's twist (InertialOptions::frame_twist_from_imu, InertialState::frameTwist)
    const std::vector<SE3d> g = tracking->guesses(frame.t_ns);
    inertial->frameTwist(ref, frame.t_ns, g.empty() ? ref.state.T_c_w : g.front(), &info.twist);
    info.twist_measured = true;
  }
  if (rolling && inertial) info.w_dot = inertial->readoutWDot(frame.t_ns);
  info.affine_guess = record->frames().empty() ? ref.state.affine : record->frames().back().affine;
  TrackResult r;
  bool ok = false;
  {
    ScopedStage st(record->stages(), "track");
    r = tracking->track(*pyr, info, &ok);
  }
  if (!ok) {
    record->addFrame(rec);
    std::ostringstream os;
    os << "tracking lost at frame " << frame.index << " (t " << io::formatSeconds(frame.t_ns) << " s): " << r.reason;
    if (tracking->lostInRow() > bo.max_lost_frames) fail(os.str());
    return FrameStatus{false, false, "tracking lost: " + r.reason};
  }
  if (r.poorly_explained && poorly_explained_frames++ == 0) first_poorly_explained = frame.index;
  rec.tracked = true;
  rec.T_c_w = r.T_c_w;
  rec.affine = r.affine;
  rec.ref_kf_id = ref.kf_id;
  rec.T_f_ref = r.T_c_w * ref.state.T_c_w.inverse();
  record->addFrame(rec);
  tracking->pushHistory(rec.t_ns, rec.T_c_w, rec.keyframe);
  fillInertial(rec.t_ns);
  // The frame's twist for the candidate tracer and, if it becomes one, the new keyframe's start: the
  // frame-to-frame velocity, with the rotation the tracker estimated where it did
  // (TrackerOptions::rotation_rate_sigma: the rate of this frame, not the mean of the last interval).
  Vec6 xi_frame = rolling ? tracking->velocityEstimate() : Vec6::Zero();
  if (rolling && r.rate_estimated) xi_frame.tail<3>() = r.twist.tail<3>();
  {
    ScopedStage st(record->stages(), "trace");
    CandidateFrame target;
    target.pose = RsFrame{r.T_c_w, xi_frame};
    if (imu_twist) inertial->frameTwist(ref, frame.t_ns, r.T_c_w, &target.pose.xi);
    target.pose.w_dot = info.w_dot;
    target.affine = r.affine;
    target.exposure_ms = frame.exposure_ms;
    window->traceCandidates(target, pyr->level(0));
  }
  KeyframeCue cue;
  cue.flow_t_px = r.flow_t_px;
  cue.flow_rt_px = r.flow_rt_px;
  cue.log_brightness_ratio = logBrightnessRatio(ref.state.affine, ref.exposure_ms, r.affine, frame.exposure_ms);
  cue.rmse = r.rmse;
  cue.first_rmse = tracking->firstRmse();
  cue.seconds_since_keyframe = nsToS(frame.t_ns - ref.t_ns);
  cue.keyframes = ref.kf_id + 1;  // the reference is the newest keyframe; kf_id counts from 0
  cue.width = camera->width();
  cue.height = camera->height();
  std::string why;
  if (!needKeyframe(bo, cue, &why)) return FrameStatus{true, false, "tracked"};
  {
    ScopedStage st(record->stages(), "keyframe");
    makeKeyframe(frame.index, frame.t_ns, frame.exposure_ms, std::move(pyr), r.T_c_w, r.affine,
                 rolling && r.rate_estimated ? &xi_frame : nullptr);
  }
  if (!failed && canRestart(frame.t_ns) && inertial->refusals() >= inertial->options().init_restart_refusals) {
    std::ostringstream os;
    os << "the visual-inertial initialisation was refused " << inertial->refusals()
       << " times (imu.init_restart_refusals " << inertial->options().init_restart_refusals
       << "; first: " << inertial->firstRefusal() << ")";
    restart(frame.index, frame.t_ns, os.str());
    return FrameStatus{false, false, "restarted: " + os.str()};
  }
  return FrameStatus{true, true, failed ? "failed: " + failure : "keyframe (" + why + ")"};
}

// DSO's makeKeyFrame order (Engel et al. 2018, sec. 3): flag keyframes to marginalise, add the keyframe
// and every active point's observation in it, activate candidates, optimise the window, set the
// tracking reference, remove outliers and marginalise leaving points, create the new keyframe's
// candidates, marginalise the flagged keyframes, check for divergence.
void Odometry::Impl::makeKeyframe(int64_t frame_index, int64_t t_ns, double exposure_ms,
                                  std::shared_ptr<const ImagePyramid> pyr, const SE3d& T_c_w,
                                  const AffineBrightness& affine, const Vec6* twist_start) {
  const std::vector<Keyframe*> flagged = window->keyframesToMarginalize();
  auto kf = std::make_unique<Keyframe>();
  kf->frame_index = frame_index;
  kf->t_ns = t_ns;
  kf->exposure_ms = exposure_ms;
  kf->pyramid = std::move(pyr);
  kf->state.T_c_w = T_c_w;
  kf->state.affine = affine;
  if (rolling) {
    kf->state.twist = twist_start ? *twist_start : tracking->velocityEstimate();
    kf->twist_start = kf->state.twist;
    MotionState ms;
    ms.t_ns = t_ns;
    ms.T_c_w = T_c_w;
    ms.twist = kf->state.twist;
    ms.is_keyframe = true;
    TwistPrior tp;
    if (tracking->twistPrior(ms, &tp)) {
      kf->has_twist_prior = true;
      kf->twist_prior = tp;
    }
  }
  if (inertial) linkInertial(*kf);
  Keyframe& nk = window->insert(std::move(kf));
  {
    ScopedStage st(record->stages(), "activate");
    window->activateCandidates(nk);
  }
  {
    ScopedStage st(record->stages(), "vi_init");
    tryInertialInitialisation();
  }
  {
    ScopedStage st(record->stages(), "optimise");
    window->optimize(bo.max_iterations);
  }
  syncLineDelay();
  if (inertial) inertial->refreshFactors(window->mutableKeyframes());
  for (const auto& k : window->keyframes()) record->recordKeyframe(*k);
  if (FrameRecord* f = record->frame(frame_index)) {
    f->keyframe = true;
    f->tracked = true;
    f->ref_kf_id = nk.kf_id;
    f->T_f_ref = SE3d();
    f->T_c_w = nk.state.T_c_w;
    f->affine = nk.state.affine;
  }
  tracking->keyframeOptimised(t_ns, nk.state.T_c_w);
  fillInertial(t_ns);
  tracking->setReference(window->trackingReference(nk));
  {
    ScopedStage st(record->stages(), "marginalise");
    window->removeOutliersAndMarginalizePoints(nk, *record);
  }
  window->createCandidates(nk);
  {
    ScopedStage st(record->stages(), "marginalise");
    for (Keyframe* f : flagged) window->marginalizeKeyframe(f, *record);
  }
  refinePhotometric(frame_index);
  checkDivergence();
}

// Online photometric estimation by alternation (interfaces/photometric.h): the rows of observations
// whose host and target were both corrected with the current parameters, once a model has enough.
// Rows that mix an earlier correction are dropped; a refinement applies from the next frame on. The
// fits see every row kept since the last change: without a change they are fitted again with more.
void Odometry::Impl::refinePhotometric(int64_t frame_index) {
  if (photometric_online.empty()) return;
  std::vector<ObservationRow>& rows = record->photometricRows();
  const int64_t since = photometric_since;
  rows.erase(std::remove_if(rows.begin(), rows.end(),
                            [since](const ObservationRow& r) { return r.frame < since || r.host < since; }),
             rows.end());
  bool changed = false;
  size_t most = 0;
  for (size_t i : photometric_online) {
    PhotometricModel& m = *photometric[i];
    most = std::max(most, m.minRowsForRefine());
    if (rows.size() < m.minRowsForRefine()) continue;
    std::string note;
    ScopedStage st(record->stages(), "photometric");
    if (m.refineFromResiduals(rows, &note)) {
      changed = true;
      const Eigen::VectorXd p = m.params();
      photometric_updates.push_back({{"slot", photometric_keys[i]},
                                     {"frame", frame_index},
                                     {"params", std::vector<double>(p.data(), p.data() + p.size())},
                                     {"note", note}});
    }
  }
  // Without a change the rows stay, so the next fit has more of them (the oldest half goes beyond ten
  // times the largest minimum).
  if (changed) {
    rows.clear();
    photometric_since = frame_index + 1;
  } else if (rows.size() > 10 * most) {
    rows.erase(rows.begin(), rows.begin() + static_cast<std::ptrdiff_t>(rows.size() / 2));
  }
}

void Odometry::Impl::syncLineDelay() {
  if (!rolling || !shutter->estimatesLineDelay()) return;
  const double ld = window->timing().line_delay_s;
  if (ld == timing.line_delay_s) return;
  timing.line_delay_s = ld;
  tracking->setTiming(timing);
}

void Odometry::Impl::checkDivergence() {
  if (failed || window->size() < 2) return;
  std::string warning;
  std::string reason = window->divergence(&warning);
  if (!warning.empty()) record->addWarning(warning);
  if (reason.empty() && inertial) reason = inertial->checkDivergence(window->keyframes());
  if (reason.empty() && rolling && shutter->estimatesLineDelay()) {
    // An estimated readout longer than 0.2 s (or not finite) is no camera's: the estimate ran away.
    const double readout_s = timing.line_delay_s * sensors.camera.height;
    if (!std::isfinite(readout_s) || std::abs(readout_s) > 0.2) {
      std::ostringstream os;
      os << "line delay diverged: the estimated readout is " << readout_s * 1e3 << " ms (|readout| > 200 ms)";
      reason = os.str();
    }
  }
  if (!reason.empty()) fail(reason);
}

// Monocular start (mono_start.h): corner tracks until a two-view pose with parallax is found, then the
// reference frame becomes the first keyframe (the gauge), its candidates are traced into the current
// frame, the current frame becomes the second keyframe through the ordinary keyframe path (activation,
// bundle adjustment), and the frames in between are tracked against it.
FrameStatus Odometry::Impl::initialise(const Frame& frame, std::shared_ptr<const ImagePyramid> pyr,
                                       const cv::Mat& working) {
  bool done = false;
  {
    ScopedStage st(record->stages(), "initialise");
    done = start->addFrame(frame, pyr, working);
  }
  const MonoInitializer& mi = start->initializer();
  if (!mi.lastSteps().empty()) record->addTrackRows(frame.index, frame.t_ns, mi.lastStepFrom(), mi.lastSteps());
  FrameRecord rec;
  rec.index = frame.index;
  rec.t_ns = frame.t_ns;
  rec.exposure_ms = frame.exposure_ms;
  if (!done) {
    record->addFrame(rec);
    const int64_t first = attempt_first_frame;
    if (frame.index - first + 1 >= bo.init_max_frames) {
      std::ostringstream os;
      os << "monocular initialisation failed after " << (frame.index - first + 1) << " frames: " << start->status();
      fail(os.str());
      return FrameStatus{false, false, "failed: " + failure};
    }
    return FrameStatus{false, false, "initialising: " + start->status()};
  }

  // The reference frame becomes keyframe 0 with the identity pose.
  ScopedStage st(record->stages(), "initialise");
  const MonoStart::StartFrame ref = start->reference();
  const SE3d T_cur_ref = start->T_cur_ref();
  if (FrameRecord* r = record->frame(ref.index)) {
    r->tracked = true;
    r->T_c_w = SE3d();
  }
  tracking->pushHistory(ref.t_ns, SE3d(), false);
  auto kf0 = std::make_unique<Keyframe>();
  kf0->frame_index = ref.index;
  kf0->t_ns = ref.t_ns;
  kf0->exposure_ms = ref.exposure_ms;
  kf0->pyramid = ref.pyramid;
  // Rolling shutter: with init_rotation_rates each frame starts with its own twist from the two-view
  // start (its rotation rate measured from its neighbour frames, mono_initializer.h); else, with
  // init_keyframe_twist, keyframe 0 starts with the start's constant twist and keyframe 1 gets it from
  // the tracking history (the same velocity, ref and cur being its two entries).
  const bool own_twists = rolling && start->ratesUsed();
  if (own_twists || (rolling && bo.init_keyframe_twist)) {
    kf0->state.twist = own_twists ? start->xiRef() : start->xi();
    kf0->twist_start = kf0->state.twist;
  }
  if (inertial) linkInertial(*kf0);
  Keyframe& k0 = window->insert(std::move(kf0));  // the first keyframe: the gauge
  if (FrameRecord* r = record->frame(ref.index)) {
    r->keyframe = true;
    r->ref_kf_id = k0.kf_id;
  }
  window->createCandidates(k0);
  // The current frame's brightness against keyframe 0 (which has a = b = 0): with affine brightness
  // estimated, the gain of the start's corners (mono_initializer.h, logGainCurRef) less the known
  // exposure ratio, as a gain only (b = 0), when it is further from 1 than
  // backend.init_affine_min_change (backend_options.h: where the trace below would lose the
  // candidates); the trace and the frame tracking search within a few grey levels of it. Else 0 (DSO's
  // coarse initialiser estimates the pair's affine brightness jointly with the depths).
  AffineBrightness affine1;
  if (estimate_affine) {
    double a = start->initializer().logGainCurRef();
    if (ref.exposure_ms > 0.0 && frame.exposure_ms > 0.0) a -= std::log(frame.exposure_ms / ref.exposure_ms);
    if (std::abs(std::exp(a) - 1.0) > bo.init_affine_min_change) affine1.a = a;
  }
  CandidateFrame target;
  target.affine = affine1;
  // The current frame's twist: its own (init_rotation_rates), else the two-view twist, or 0.
  target.pose = RsFrame{T_cur_ref, own_twists ? start->xiCur() : k0.state.twist};
  if (rolling && inertial) target.pose.w_dot = inertial->readoutWDot(frame.t_ns);
  target.exposure_ms = frame.exposure_ms;
  window->traceCandidates(target, pyr->level(0));
  record->recordKeyframe(k0);

  // The current frame: a tracked frame that becomes keyframe 1.
  rec.tracked = true;
  rec.T_c_w = T_cur_ref;
  rec.ref_kf_id = k0.kf_id;
  rec.T_f_ref = T_cur_ref;
  record->addFrame(rec);
  tracking->pushHistory(rec.t_ns, rec.T_c_w, rec.keyframe);
  const Vec6 xi_cur = start->xiCur();
  makeKeyframe(frame.index, frame.t_ns, frame.exposure_ms, pyr, T_cur_ref, affine1, own_twists ? &xi_cur : nullptr);
  initialized = true;
  if (failed) return FrameStatus{false, true, "failed: " + failure};

  // Frames between the two keyframes: tracked against keyframe 1 from poses interpolated in time.
  const SE3d T1 = window->newest().state.T_c_w;
  const int64_t kf1_id = window->newest().kf_id;
  const Vec6 log_rel = T1.log();  // keyframe 0 is the identity
  const double span = nsToS(frame.t_ns - ref.t_ns);
  for (const MonoStart::StartFrame& f : start->frames()) {
    if (f.index == ref.index || f.index == frame.index || f.working.empty()) continue;
    const ImagePyramid p(f.working, fo.pyramid_levels);
    TrackingFrame info;
    info.t_ns = f.t_ns;
    info.exposure_ms = f.exposure_ms;
    if (rolling && inertial) info.w_dot = inertial->readoutWDot(f.t_ns);
    const double s = span > 0 ? nsToS(f.t_ns - ref.t_ns) / span : 0.5;
    info.affine_guess.a = s * affine1.a;  // between keyframe 0's (0) and keyframe 1's start, by time
    const TrackResult r = tracking->trackFrom(p, info, {SE3d::exp(log_rel * s)});
    if (!r.ok()) continue;
    if (FrameRecord* fr = record->frame(f.index)) {
      fr->tracked = true;
      fr->T_c_w = r.T_c_w;
      fr->affine = r.affine;
      fr->ref_kf_id = kf1_id;
      fr->T_f_ref = r.T_c_w * T1.inverse();
    }
  }
  start->clear();
  tracking->resetFirstRmse();
  std::ostringstream os;
  os << "initialised (" << start->status() << ")";
  return FrameStatus{true, true, os.str()};
}

void Odometry::Impl::finish() {
  record->setProvisional(false);
  // A late initialisation after many refusals: the start's keyframe poses did not fit the IMU
  // (InertialOptions::init_refusals_warn). Not a failure: the run after it may be sound.
  if (inertial && inertial->initialised() && inertial->options().init_refusals_warn > 0 &&
      inertial->refusals() >= inertial->options().init_refusals_warn) {
    std::ostringstream os;
    os << "the visual-inertial initialisation succeeded only at t " << io::formatSeconds(vi_init_t_ns) << " s, after "
       << inertial->refusals() << " refused attempts since t " << io::formatSeconds(inertial->firstRefusalNs())
       << " s (imu.init_refusals_warn " << inertial->options().init_refusals_warn << "; first: "
       << inertial->firstRefusal()
       << "): the keyframe poses of the run's start did not fit the IMU, and the trajectory before the "
          "initialisation may be broken";
    record->addWarning(os.str());
  }
  if (inertial) {
    const std::string w = inertial->residualWarning();
    if (!w.empty()) record->addWarning(w);
  }
  if (poorly_explained_frames > 0) {
    std::ostringstream os;
    os << poorly_explained_frames << " of " << record->frames().size()
       << " frames were tracked with an explained ratio below frontend.track_min_explained_ratio (first: frame "
       << first_poorly_explained
       << "), kept as they fell gradually: the model explains these images poorly; rsvio diagnose on this run "
          "looks for the effect it lacks";
    record->addWarning(os.str());
  }
  if (!initialized && !failed) {
    // The sequence ended before the monocular start succeeded: nothing was estimated, and saying
    // "ok" would hide it.
    std::ostringstream os;
    if (restarts.empty())
      os << "monocular initialisation did not succeed in the " << record->frames().size()
         << " frames of the sequence: " << start->status();
    else
      os << "monocular initialisation did not succeed in the "
         << (record->frames().empty() || attempt_first_frame < 0 ? 0 : record->frames().back().index - attempt_first_frame + 1)
         << " frames since the start was begun again (" << restarts.size() << " restarts): " << start->status();
    fail(os.str());
  }
  if (window->empty()) return;
  if (!failed && window->size() >= 2) {
    ScopedStage st(record->stages(), "optimise");
    window->optimize(bo.max_iterations);
    syncLineDelay();
  }
  window->evaluate();
  for (const auto& kf : window->keyframes()) record->recordFinal(*kf);
  window->releasePoints(*record);
}

Odometry::Odometry(const nlohmann::json& effective_config, PluginHost& host, const SensorSetup& sensors)
    : impl_(new Impl(effective_config, host, sensors)) {}

Odometry::~Odometry() = default;

void Odometry::addImu(const ImuSample& sample) {
  for (auto& m : impl_->motion) m->addImu(sample);
  if (impl_->inertial) impl_->inertial->addImu(sample);
}

FrameStatus Odometry::addFrame(const Frame& frame) {
  Impl& m = *impl_;
  if (m.failed) return FrameStatus{false, false, "failed: " + m.failure};
  if (frame.image.cols != m.camera->width() || frame.image.rows != m.camera->height()) {
    std::ostringstream os;
    os << "frame " << frame.index << (frame.path.empty() ? "" : " (" + frame.path + ")") << ": image is "
       << frame.image.cols << "x" << frame.image.rows << ", the calibration says " << m.camera->width() << "x"
       << m.camera->height();
    throw DataError(os.str());
  }
  try {
    cv::Mat working;
    std::shared_ptr<const ImagePyramid> pyr;
    {
      ScopedStage st(m.record->stages(), "preprocess");
      working = prepareWorkingImage(frame, m.photometric_ptrs);
      pyr = std::make_shared<ImagePyramid>(working, m.fo.pyramid_levels);
    }
    if (m.attempt_first_frame < 0) {
      m.attempt_first_frame = frame.index;
      m.attempt_t0_ns = frame.t_ns;
    }
    FrameStatus st = m.initialized ? m.track(frame, std::move(pyr)) : m.initialise(frame, std::move(pyr), working);
    return m.afterFrame(frame, std::move(st));
  } catch (const DataError&) {
    throw;
  } catch (const Error& e) {
    m.fail(std::string("frame ") + std::to_string(frame.index) + ": " + e.what());
    return m.afterFrame(frame, FrameStatus{false, false, "failed: " + m.failure});
  }
}

// A failed attempt that may still be restarted is restarted instead; the record stays provisional
// only while a restart may come.
FrameStatus Odometry::Impl::afterFrame(const Frame& frame, FrameStatus st) {
  if (failed && canRestart(frame.t_ns)) {
    const std::string why = "the attempt failed: " + failure;
    restart(frame.index, frame.t_ns, why);
    return FrameStatus{false, false, "restarted: " + why};
  }
  if (record->provisional() && !canRestart(frame.t_ns))
    record->setProvisional(false);
  return st;
}

void Odometry::finish() { impl_->finish(); }

bool Odometry::failed() const { return impl_->failed; }
std::string Odometry::failureReason() const { return impl_->failure; }
std::map<std::string, double> Odometry::stageMs() const { return impl_->record->stages().means(); }
long Odometry::numKeyframes() const { return impl_->record->numKeyframes(); }
bool Odometry::usesImu() const { return impl_->inertial && impl_->inertial->initialised(); }
double Odometry::scale() const { return usesImu() ? impl_->inertial->scale() : 1.0; }
nlohmann::json Odometry::inertialReport() const {
  const Impl& m = *impl_;
  if (!m.inertial) return nullptr;
  nlohmann::json j;
  j["initialised"] = m.inertial->initialised();
  j["status"] = m.inertial->status();
  j["init_refusals"] = m.inertial->refusals();  // of the kept attempt
  if (m.inertial->options().init_restart_refusals > 0) j["start_restarts"] = m.restarts;
  if (m.inertial->refusals() > 0) {
    j["init_first_refusal_at_s"] = nsToS(m.inertial->firstRefusalNs());
    j["init_first_refusal"] = m.inertial->firstRefusal();
  }
  if (m.inertial->initialised()) {
    j["initialised_at_s"] = nsToS(m.vi_init_t_ns);
    j["scale_at_initialisation"] = m.inertial->initialScale();
    j["scale"] = m.inertial->scale();
    const Vec3 g = m.inertial->globals().state.T_wm_wf.so3().inverse() * Vec3(0, 0, -1);
    j["gravity_direction_wf"] = {g.x(), g.y(), g.z()};
  }
  const DynamicMarginalization& dm = m.window->marginalization();
  if (dm.options().enabled) {
    nlohmann::json d;
    d["interval"] = dm.options().interval;
    d["switches"] = dm.numSwitches();
    d["half_resets"] = dm.numHalfResets();
    d["centre"] = dm.centre();
    nlohmann::json ev = nlohmann::json::array();
    for (const auto& e : dm.events())
      ev.push_back({{"t_s", e.t_s}, {"event", eventName(e.event)}, {"scale", e.scale}, {"centre", e.s_mid}});
    d["events"] = ev;
    j["dynamic_marginalization"] = d;
  }
  j["time_offset_estimated"] = m.inertial->options().estimate_time_offset;
  j["time_offset_ms"] = m.inertial->timeOffset() * 1e3;
  return j;
}
nlohmann::json Odometry::photometricReport() const {
  const Impl& m = *impl_;
  if (m.photometric_online.empty()) return nullptr;
  nlohmann::json j;
  for (size_t i : m.photometric_online) {
    const Eigen::VectorXd p = m.photometric[i]->params();
    j[m.photometric_keys[i]] = {{"estimated_online", true},
                                {"params", std::vector<double>(p.data(), p.data() + p.size())}};
  }
  j["updates"] = m.photometric_updates;
  return j;
}
nlohmann::json Odometry::shutterReport() const {
  const Impl& m = *impl_;
  if (!m.rolling) return nullptr;
  nlohmann::json j;
  const double rows = static_cast<double>(m.sensors.camera.height);
  j["line_delay_estimated"] = m.shutter->estimatesLineDelay();
  j["line_delay_us"] = m.timing.line_delay_s * 1e6;
  j["readout_ms"] = m.timing.line_delay_s * rows * 1e3;
  if (m.shutter->estimatesLineDelay()) j["line_delay_us_start"] = m.line_delay_start_s * 1e6;
  j["twist_rescued_frames"] = m.tracking->twistRescues();  // tracked or explained better by a twist retry (tracking.h)
  return j;
}
std::vector<std::string> Odometry::warnings() const { return impl_->record->warnings(); }
const DiagnosticsLog& Odometry::diagnostics() const { return impl_->record->diagnostics(); }
void Odometry::takeDiagnostics(std::vector<ObservationRow>* rows) { impl_->record->takeObservations(rows); }
// Visual-inertial: points go out in W_m, mapped with their host keyframe's scale and the current gravity
// rotation (points taken before the initialisation stay in W_f; run_record.h, docs/vio.md).
void Odometry::takePoints(std::vector<MapPoint>* points) { impl_->record->takePoints(points); }

io::Trajectory Odometry::frameTrajectory() const {
  std::vector<RxSO3d> T;
  io::Trajectory t = impl_->record->frameTrajectory(impl_->window->keyframes(), &T);
  return impl_->toBody(std::move(t), T);
}
io::Trajectory Odometry::keyframeTrajectory() const {
  std::vector<RxSO3d> T;
  io::Trajectory t = impl_->record->keyframeTrajectory(impl_->window->keyframes(), &T);
  return impl_->toBody(std::move(t), T);
}
std::vector<MapPoint> Odometry::points() const { return impl_->record->points(impl_->window->keyframes()); }
std::vector<StateRow> Odometry::states() const {
  return impl_->record->states(impl_->window->keyframes());
}

}  // namespace rsvio
