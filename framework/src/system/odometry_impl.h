// Private state of rsvio::Odometry, shared by odometry.cpp (set-up, frame loop), odometry_keyframe.cpp
// (keyframes, points, marginalisation), odometry_init.cpp (monocular start) and odometry_output.cpp
// (trajectories, points, states, diagnostics).
#pragma once
#include <chrono>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "rsvio/backend/backend_options.h"
#include "rsvio/backend/bundle_adjustment.h"
#include "rsvio/backend/marginalization.h"
#include "rsvio/backend/mono_initializer.h"
#include "rsvio/backend/smooth_motion_term.h"
#include "rsvio/backend/window.h"
#include "rsvio/frontend/candidate_points.h"
#include "rsvio/frontend/frame_tracker.h"
#include "rsvio/frontend/frontend_options.h"
#include "rsvio/interfaces/camera.h"
#include "rsvio/interfaces/motion_prior.h"
#include "rsvio/interfaces/photometric.h"
#include "rsvio/interfaces/shutter.h"
#include "rsvio/interfaces/solver.h"
#include "rsvio/photometric/image_pyramid.h"
#include "rsvio/system/odometry.h"

namespace rsvio {

// One input frame as the estimator remembers it.
struct FrameRecord {
  int64_t index = 0;
  int64_t t_ns = 0;
  bool tracked = false;
  bool keyframe = false;
  int64_t ref_kf_id = -1;     // the keyframe it was tracked against (itself for a keyframe)
  SE3d T_f_ref;               // camera of this frame from the camera of the reference keyframe
  SE3d T_c_w;                 // as estimated when tracked (keyframes: updated by their optimisation)
  AffineBrightness affine;
  double exposure_ms = std::numeric_limits<double>::quiet_NaN();
};

// A keyframe's latest (for marginalised ones: final) state.
struct KeyframeRecord {
  int64_t kf_id = 0;
  int64_t frame_index = 0;
  int64_t t_ns = 0;
  KeyframeState state;
};

// Mean wall time per call of each stage.
class StageTimes {
 public:
  void add(const std::string& stage, double ms) {
    auto& s = stages_[stage];
    s.first += ms;
    s.second += 1;
  }
  std::map<std::string, double> means() const {
    std::map<std::string, double> out;
    for (const auto& [k, v] : stages_) out[k] = v.second > 0 ? v.first / static_cast<double>(v.second) : 0.0;
    return out;
  }

 private:
  std::map<std::string, std::pair<double, long>> stages_;
};

class ScopedStage {
 public:
  ScopedStage(StageTimes& t, const char* stage) : t_(t), stage_(stage), t0_(std::chrono::steady_clock::now()) {}
  ~ScopedStage() {
    t_.add(stage_, std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0_).count());
  }

 private:
  StageTimes& t_;
  const char* stage_;
  std::chrono::steady_clock::time_point t0_;
};

struct Odometry::Impl {
  // Configuration.
  nlohmann::json config;
  BackendOptions bo;
  FrontendOptions fo;
  int threads = 1;
  uint64_t seed = 0;
  SensorSetup sensors;
  // Plugins.
  std::unique_ptr<CameraModel> camera;
  std::unique_ptr<ShutterModel> shutter;
  std::unique_ptr<SolverBackend> solver;
  std::vector<std::unique_ptr<PhotometricModel>> photometric;
  std::vector<const PhotometricModel*> photometric_ptrs;
  std::vector<std::unique_ptr<MotionPrior>> motion;
  RowTiming timing;
  bool rolling = false;
  bool estimate_affine = false;
  // Front end and back end.
  std::unique_ptr<FrameTracker> tracker;
  std::unique_ptr<CandidateTracer> tracer;
  std::unique_ptr<BundleAdjuster> ba;
  std::unique_ptr<SmoothMotionTerm> smooth_motion;  // rolling shutter with a smooth-motion prior, else null
  std::unique_ptr<MarginalizationPrior> prior;
  std::unique_ptr<MonoInitializer> initializer;
  KeyframeList window;
  // Run state.
  bool initialized = false;
  bool failed = false;
  std::string failure;
  int lost_in_row = 0;
  int64_t next_kf_id = 0;
  int64_t next_point_id = 0;
  int64_t first_kf_id = -1;
  double min_act_dist = 2.0;
  double first_rmse = std::nan("");     // first tracking RMSE against the current reference
  double initial_median_idepth = 0.0;   // for the scale-collapse test
  std::vector<FrameRecord> frames;
  std::map<int64_t, KeyframeRecord> keyframes;  // by kf_id, every keyframe of the run
  std::vector<MotionState> history;              // recent tracked frames, for the motion priors
  std::vector<MapPoint> map_points;              // points that left the window (marginalised)
  DiagnosticsLog diag;
  StageTimes stages;
  std::vector<std::string> warnings;
  BundleAdjustmentStats last_ba;
  // Initialisation: frames since the initializer's reference (working images, to re-track them).
  struct InitFrame {
    int64_t index = 0, t_ns = 0;
    double exposure_ms = std::nan("");
    std::shared_ptr<const ImagePyramid> pyramid;  // only the reference keeps its pyramid
    cv::Mat working;
  };
  std::vector<InitFrame> init_frames;

  Impl(const nlohmann::json& cfg, PluginHost& host, const SensorSetup& s);

  // odometry.cpp
  FrameStatus track(const Frame& frame, std::shared_ptr<const ImagePyramid> pyr);
  void fail(const std::string& reason);
  std::vector<SE3d> guesses(int64_t t_ns) const;
  Vec6 velocityEstimate() const;  // per second, from the last two tracked frames (0 without)
  Vec6 frameTwistGuess() const;   // rolling shutter: a new frame's twist (see odometry.cpp)
  void pushHistory(const FrameRecord& f);

  // odometry_init.cpp
  FrameStatus initialise(const Frame& frame, std::shared_ptr<const ImagePyramid> pyr, const cv::Mat& working);

  // odometry_keyframe.cpp
  void makeKeyframe(int64_t frame_index, int64_t t_ns, double exposure_ms, std::shared_ptr<const ImagePyramid> pyr,
                    const SE3d& T_c_w, const AffineBrightness& affine);
  void traceCandidates(const ImagePyramid& pyr, const SE3d& T_c_w, const AffineBrightness& affine,
                       double exposure_ms);
  void activateCandidates(Keyframe& newest);
  void removeOutliersAndMarginalizePoints(Keyframe& newest);
  void marginalizeKeyframe(Keyframe* kf);
  void linkMotionNeighbours(Keyframe& kf);
  void marginalizeMotionTerms(const Keyframe* leaving);
  void createCandidates(Keyframe& kf);
  void setTrackingReference(const Keyframe& newest);
  void checkDivergence();
  int numActivePoints() const;
  double medianIdepth() const;

  // odometry_output.cpp
  void logObservation(const ActivePoint& p, const ActiveObservation& o);
  void recordPoint(const ActivePoint& p);
  void recordKeyframe(const Keyframe& kf);
  Vec6 observedTwist(Keyframe& kf) const;
};

}  // namespace rsvio
