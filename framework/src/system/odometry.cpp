// The estimator behind `rsvio run` (contract in rsvio/system/odometry.h): set-up from the effective
// config, the per-frame loop (preprocess, track, trace candidates, keyframe decision) and the results.
// Keyframes and points: odometry_keyframe.cpp; monocular start: odometry_init.cpp; outputs:
// odometry_output.cpp.
#include <algorithm>
#include <cmath>
#include <sstream>

#include "odometry_impl.h"
#include "rsvio/backend/keyframe_policy.h"
#include "rsvio/config/validate.h"
#include "rsvio/core/error.h"
#include "rsvio/core/time.h"
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
      photometric.push_back(makeSlot<PhotometricModel>(host, cfg, "photometric." + it.key()));
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
  std::vector<ConfigProblem> problems;
  const nlohmann::json fe = validateParams(cfg.contains("frontend") ? cfg.at("frontend") : nlohmann::json::object(),
                                           frontendParamTable(), "frontend", problems);
  if (!problems.empty()) {
    std::string msg = "frontend: " + std::to_string(problems.size()) + " problem(s)";
    for (const ConfigProblem& p : problems) msg += "\n" + p.str();
    throw ConfigError(msg);
  }
  fo = frontendOptions(Params(fe, "frontend"), seed, threads);
  bo = backendOptionsFromConfig(cfg);

  timing = RowTiming::from(*shutter, *camera);
  rolling = shutter->isRolling();
  BundleAdjustmentConfig bc;
  for (const PhotometricModel* p : photometric_ptrs)
    if (p->hasAffineBrightness()) {
      estimate_affine = true;
      bc.affine_prior_a = p->affinePriorA();
      bc.affine_prior_b = p->affinePriorB();
    }
  TrackerOptions to = fo.track;
  to.residual = fo.residual;
  to.estimate_a = to.estimate_b = estimate_affine;
  to.threads = threads;
  tracker = std::make_unique<FrameTracker>(to, *camera, timing);
  tracer = std::make_unique<CandidateTracer>(fo.trace, fo.residual, *camera, timing);
  bc.layout.rolling = rolling;
  bc.residual = fo.residual;
  bc.estimate_affine = estimate_affine;
  bc.lambda_initial = bo.lambda_initial;
  bc.step_threshold = bo.step_threshold;
  bc.twist_regularization = bo.twist_regularization;
  bc.threads = threads;
  ba = std::make_unique<BundleAdjuster>(bc, *camera, timing, *solver);
  if (rolling) {
    Mat6 info;
    for (const auto& m : motion)
      if (m->smoothMotionInformation(&info)) {
        SmoothMotionOptions so;
        so.information = info;
        smooth_motion = std::make_unique<SmoothMotionTerm>(so);
        ba->setTerms({smooth_motion.get()});
        break;
      }
  }
  prior = std::make_unique<MarginalizationPrior>(bc.layout);
  initializer = std::make_unique<MonoInitializer>(bo, *camera);
  min_act_dist = bo.activation_min_dist_px;
  diag.width = sensors.camera.width;
  diag.height = sensors.camera.height;
  diag.line_delay_s = rolling ? timing.line_delay_s : 0.0;
  if (sensors.has_imu)
    warnings.push_back("the dataset has an IMU; this estimator runs pure visual odometry (IMU ignored)");
}

void Odometry::Impl::fail(const std::string& reason) {
  if (failed) return;
  failed = true;
  failure = reason;
}

Vec6 Odometry::Impl::velocityEstimate() const {
  if (history.size() < 2) return Vec6::Zero();
  const MotionState& a = history[history.size() - 2];
  const MotionState& b = history.back();
  const double dt = nsToS(b.t_ns - a.t_ns);
  if (!(std::abs(dt) > 1e-9)) return Vec6::Zero();
  return (b.T_c_w * a.T_c_w.inverse()).log() / dt;
}

// The twist of a new frame (rolling shutter), held fixed by the tracker:
// rotation from the frame-to-frame velocity of the last two tracked frames, translation from the
// newest keyframe's optimised twist. Tracking determines rotation well over one frame interval, but
// its translation over 50 ms is noisy (demo sequence: +-0.3 m/s against 0.6 m/s of motion), and a
// twist's translation is nearly unobservable by the tracker itself; the window's twist is held by
// the smooth-motion term (smooth_motion_term.h). Measured on the demo sequence (rs_vo, true line
// delay, docs/rolling_shutter.md): frame-to-frame twist 71 mm ATE, this mix 14 mm. The candidate
// tracer and a new keyframe's starting twist keep the frame-to-frame velocity (the same mix there
// measured 89 and 18 mm on that sequence).
Vec6 Odometry::Impl::frameTwistGuess() const {
  Vec6 xi = velocityEstimate();
  if (!window.empty()) xi.head<3>() = window.back()->state.twist.head<3>();
  return xi;
}

void Odometry::Impl::pushHistory(const FrameRecord& f) {
  MotionState s;
  s.t_ns = f.t_ns;
  s.T_c_w = f.T_c_w;
  s.is_keyframe = f.keyframe;
  history.push_back(s);
  if (history.size() > 2) history.back().twist = velocityEstimate();
  constexpr size_t kHistory = 32;
  if (history.size() > kHistory) history.erase(history.begin(), history.begin() + (history.size() - kHistory));
}

std::vector<SE3d> Odometry::Impl::guesses(int64_t t_ns) const {
  std::vector<SE3d> out;
  for (const auto& m : motion) {
    const std::vector<SE3d> g = m->predict(history, t_ns);
    out.insert(out.end(), g.begin(), g.end());
  }
  if (out.empty() && !history.empty()) out.push_back(history.back().T_c_w);
  return out;
}

FrameStatus Odometry::Impl::track(const Frame& frame, std::shared_ptr<const ImagePyramid> pyr) {
  const Keyframe& ref = *window.back();
  FrameRecord rec;
  rec.index = frame.index;
  rec.t_ns = frame.t_ns;
  rec.exposure_ms = frame.exposure_ms;
  TrackingFrame info;
  info.t_ns = frame.t_ns;
  info.exposure_ms = frame.exposure_ms;
  info.twist = rolling ? frameTwistGuess() : Vec6::Zero();
  info.affine_guess = frames.empty() ? ref.state.affine : frames.back().affine;
  TrackResult r;
  {
    ScopedStage st(stages, "track");
    r = tracker->track(*pyr, info, guesses(frame.t_ns));
  }
  if (!r.ok() || !r.T_c_w.translation().allFinite()) {
    frames.push_back(rec);
    ++lost_in_row;
    std::ostringstream os;
    os << "tracking lost at frame " << frame.index << " (t " << io::formatSeconds(frame.t_ns) << " s): " << r.reason;
    if (lost_in_row > bo.max_lost_frames) fail(os.str());
    return FrameStatus{false, false, "tracking lost: " + r.reason};
  }
  lost_in_row = 0;
  if (std::isnan(first_rmse)) first_rmse = r.rmse;
  rec.tracked = true;
  rec.T_c_w = r.T_c_w;
  rec.affine = r.affine;
  rec.ref_kf_id = ref.kf_id;
  rec.T_f_ref = r.T_c_w * ref.state.T_c_w.inverse();
  frames.push_back(rec);
  pushHistory(rec);
  {
    ScopedStage st(stages, "trace");
    traceCandidates(*pyr, r.T_c_w, r.affine, frame.exposure_ms);
  }
  KeyframeCue cue;
  cue.flow_t_px = r.flow_t_px;
  cue.flow_rt_px = r.flow_rt_px;
  cue.log_brightness_ratio = logBrightnessRatio(ref.state.affine, ref.exposure_ms, r.affine, frame.exposure_ms);
  cue.rmse = r.rmse;
  cue.first_rmse = first_rmse;
  cue.seconds_since_keyframe = nsToS(frame.t_ns - ref.t_ns);
  cue.width = camera->width();
  cue.height = camera->height();
  std::string why;
  if (!needKeyframe(bo, cue, &why)) return FrameStatus{true, false, "tracked"};
  {
    ScopedStage st(stages, "keyframe");
    makeKeyframe(frame.index, frame.t_ns, frame.exposure_ms, std::move(pyr), r.T_c_w, r.affine);
  }
  return FrameStatus{true, true, failed ? "failed: " + failure : "keyframe (" + why + ")"};
}

Odometry::Odometry(const nlohmann::json& effective_config, PluginHost& host, const SensorSetup& sensors)
    : impl_(new Impl(effective_config, host, sensors)) {}

Odometry::~Odometry() = default;

void Odometry::addImu(const ImuSample& sample) {
  for (auto& m : impl_->motion) m->addImu(sample);
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
      ScopedStage st(m.stages, "preprocess");
      working = prepareWorkingImage(frame, m.photometric_ptrs);
      pyr = std::make_shared<ImagePyramid>(working, m.fo.pyramid_levels);
    }
    if (!m.initialized) return m.initialise(frame, std::move(pyr), working);
    return m.track(frame, std::move(pyr));
  } catch (const DataError&) {
    throw;
  } catch (const Error& e) {
    m.fail(std::string("frame ") + std::to_string(frame.index) + ": " + e.what());
    return FrameStatus{false, false, "failed: " + m.failure};
  }
}

bool Odometry::failed() const { return impl_->failed; }
std::string Odometry::failureReason() const { return impl_->failure; }
std::map<std::string, double> Odometry::stageMs() const { return impl_->stages.means(); }
long Odometry::numKeyframes() const { return static_cast<long>(impl_->keyframes.size()); }
bool Odometry::usesImu() const { return false; }
double Odometry::scale() const { return 1.0; }
std::vector<std::string> Odometry::warnings() const { return impl_->warnings; }
const DiagnosticsLog& Odometry::diagnostics() const { return impl_->diag; }

}  // namespace rsvio
