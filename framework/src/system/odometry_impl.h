// Private state of rsvio::Odometry (contract in rsvio/system/odometry.h): the configuration, the
// plugins, and the parts it composes, each a class owning its invariants (header comments there):
//
//   (a) KeyframeWindow  keyframe_window.h  keyframes, active points and candidates, bundle adjustment,
//                                          marginalisation prior, smooth-motion terms
//   (b) RunRecord       run_record.h       frame/keyframe records, map points, diagnostics rows,
//                                          stage times, warnings: what the outputs are written from
//   (c) Tracking        tracking.h         frame tracker and its reference, motion history, guesses
//   (d) MonoStart       mono_start.h       the monocular initialiser and its frames
//   (e) InertialState   inertial_state.h   visual-inertial runs only: IMU buffer, per-keyframe velocity and
//                                          biases, T_Wm_Wf (scale and gravity), time offset, IMU
//                                          factors and twist energy; fed by addImu(), its terms reach
//                                          the window's optimisation as a WindowTerm
//                                          (backend/bundle_adjustment.h), as the smooth-motion term does.
//
// Odometry::Impl (odometry.cpp) is the frame loop and the order of things: it decides keyframes,
// calls the parts in DSO's makeKeyFrame order and keeps the run's status (initialised, failed). A start
// that is begun again (InertialOptions::init_restart_refusals) gets a new window, tracking and monocular
// start, and an inertial state with only the old one's IMU buffer; the record stays and drops the attempt.
// The parts do not know each other, except that the window hands what leaves it to a WindowSink
// (the run record).
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "inertial_state.h"
#include "keyframe_window.h"
#include "mono_start.h"
#include "rsvio/backend/backend_options.h"
#include "rsvio/frontend/frontend_options.h"
#include "rsvio/interfaces/camera.h"
#include "rsvio/interfaces/motion_prior.h"
#include "rsvio/interfaces/photometric.h"
#include "rsvio/interfaces/shutter.h"
#include "rsvio/interfaces/solver.h"
#include "rsvio/photometric/image_pyramid.h"
#include "rsvio/system/odometry.h"
#include "run_record.h"
#include "tracking.h"

namespace rsvio {

struct Odometry::Impl {
  // Configuration.
  nlohmann::json config;
  BackendOptions bo;
  FrontendOptions fo;
  int threads = 1;
  uint64_t seed = 0;
  SensorSetup sensors;
  // Plugins (declared before the parts, which hold references to them).
  std::unique_ptr<CameraModel> camera;
  std::unique_ptr<ShutterModel> shutter;
  std::unique_ptr<SolverBackend> solver;
  std::vector<std::unique_ptr<PhotometricModel>> photometric;
  std::vector<const PhotometricModel*> photometric_ptrs;
  std::vector<std::string> photometric_keys;  // their config slots ("photometric.<name>"), same order
  // Photometric models estimated online (indices into photometric), the first frame corrected with
  // their current parameters, and what each refinement changed (report.json "photometric").
  std::vector<size_t> photometric_online;
  int64_t photometric_since = 0;
  nlohmann::json photometric_updates = nlohmann::json::array();
  std::vector<std::unique_ptr<MotionPrior>> motion;
  RowTiming timing;             // the shutter's; its line delay follows the window's when estimated
  double line_delay_start_s = 0.0;
  bool rolling = false;
  bool estimate_affine = false;
  // The parts.
  std::unique_ptr<RunRecord> record;       // (b)
  std::unique_ptr<Tracking> tracking;      // (c)
  std::unique_ptr<KeyframeWindow> window;  // (a)
  std::unique_ptr<MonoStart> start;        // (d)
  std::unique_ptr<InertialState> inertial; // (e) null for visual odometry
  // What the parts are made from (kept for a restart).
  WindowSetup window_setup;
  TrackerOptions tracker_options;
  std::vector<const MotionPrior*> motion_ptrs;
  // Run status.
  bool initialized = false;
  bool failed = false;
  std::string failure;
  int64_t vi_init_t_ns = -1;  // the keyframe time of the visual-inertial initialisation
  // Frames tracked although the model explained them poorly (TrackResult::poorly_explained): a warning
  // at the end, and a hint for rsvio diagnose.
  int64_t poorly_explained_frames = 0;
  int64_t first_poorly_explained = -1;
  // Restarts of the start (InertialOptions::init_restart_refusals): the current attempt's first frame
  // and its time (-1: none yet), and each restart (report.json extra.vio start_restarts).
  int64_t attempt_first_frame = -1;
  int64_t attempt_t0_ns = -1;
  nlohmann::json restarts = nlohmann::json::array();

  Impl(const nlohmann::json& cfg, PluginHost& host, const SensorSetup& s);
  // The tracking and monocular start from tracker_options and motion_ptrs, and the window (made by the
  // caller from window_setup) wired to the inertial state (when there is one) and the record.
  void makeParts();
  // A restart may still happen at camera time t_ns (the contract of InertialOptions::init_restart_refusals).
  bool canRestart(int64_t t_ns) const;
  // Discards the attempt (RunRecord::restart), makes the parts afresh (the inertial state keeps its IMU
  // buffer) and waits for a new monocular start from the next frame.
  void restart(int64_t frame_index, int64_t t_ns, const std::string& why);
  // After each frame: a failed attempt restarted where it may be, the record's provisional flag.
  FrameStatus afterFrame(const Frame& frame, FrameStatus st);

  FrameStatus initialise(const Frame& frame, std::shared_ptr<const ImagePyramid> pyr, const cv::Mat& working);
  FrameStatus track(const Frame& frame, std::shared_ptr<const ImagePyramid> pyr);
  void makeKeyframe(int64_t frame_index, int64_t t_ns, double exposure_ms, std::shared_ptr<const ImagePyramid> pyr,
                    const SE3d& T_c_w, const AffineBrightness& affine, const Vec6* twist_start = nullptr);
  void checkDivergence();
  // After a keyframe: hands the online photometric models the rows of images corrected with their
  // current parameters (PhotometricModel::refineFromResiduals).
  void refinePhotometric(int64_t frame_index);
  // An estimated line delay: the window's current value to the timing the tracker and record use.
  void syncLineDelay();
  void tryInertialInitialisation();
  void fillInertial(int64_t t_ns);  // the history entry of t_ns gets its inertial fields (VIO)
  void linkInertial(Keyframe& kf);  // a new keyframe's inertial terms and smooth-motion weights (VIO)
  // Camera poses in W_f -> body poses in W_m (VIO, after the initialisation), pose i with T_wm_wf[i]
  // (RunRecord's per-pose transforms).
  io::Trajectory toBody(io::Trajectory t, const std::vector<RxSO3d>& T_wm_wf) const;
  void finish();
  void fail(const std::string& reason);
};

}  // namespace rsvio
