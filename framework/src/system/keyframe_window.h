// The sliding window of rsvio::Odometry (docs/backend.md): the keyframes and their active points and
// candidates, the bundle adjuster over them, the marginalisation prior and the smooth-motion terms.
// The start of DSO's FullSystem window handling (makeKeyFrame's order, Engel et al. 2018, sec. 3),
// without the frame loop, the outputs or the monocular start (odometry.cpp composes them).
//
// Owns
// - the keyframes (KeyframeList, oldest first; Keyframe* stays valid until the keyframe leaves) with
//   their active points (backend/window.h) and candidate points (frontend/candidate_points.h);
// - the candidate tracer, the bundle adjuster, the marginalisation prior (FEJ, marginalization.h; with
//   dynamic marginalisation, the three priors of dynamic_marginalization.h, switched after each
//   optimisation of a visual-inertial run by the scale estimate) and,
//   for a rolling shutter with a smooth-motion prior, the smooth-motion term (smooth_motion_term.h);
// - the counters that make ids unique over the run (kf_id, point id), the run's first keyframe (the
//   gauge), DSO's adaptive activation distance, the last optimisation's statistics and the median
//   inverse depth at the start (for the scale-collapse test).
//
// Invariants
// - kf_id and point ids grow in creation order; exactly one keyframe, the run's first, is the gauge.
// - Every active point has at most one observation per other keyframe in the window and none in its
//   host; a keyframe joining the window gets an observation of every active point (insert()).
// - Whatever leaves the window leaves through a WindowSink, in the order it leaves: an inlier
//   observation at its final linearisation, a marginalised point, a marginalised keyframe's final
//   state. What the prior holds about a leaving keyframe or point is added before it is removed.
// - A smooth-motion term is active only while its keyframe and its neighbours are in the window; a
//   term touching a leaving keyframe goes into the prior first (marginalizeMotionTerms). The same holds
//   for the inertial terms of a visual-inertial run (inertial_state.h), which the window hands to the
//   prior through the InertialState given by setInertial() before a keyframe's block is marginalised.
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "rsvio/backend/backend_options.h"
#include "rsvio/backend/bundle_adjustment.h"
#include "rsvio/backend/dynamic_marginalization.h"
#include "rsvio/backend/smooth_motion_term.h"
#include "rsvio/backend/window.h"
#include "rsvio/frontend/block_runner.h"
#include "rsvio/frontend/candidate_points.h"
#include "rsvio/frontend/frame_tracker.h"
#include "rsvio/frontend/frontend_options.h"
#include "rsvio/interfaces/camera.h"
#include "rsvio/interfaces/solver.h"
#include "inertial_state.h"

namespace rsvio {

// Receives what leaves the window (the run record, run_record.h, implements it).
class WindowSink {
 public:
  virtual ~WindowSink() = default;
  // An observation of p at its last linearisation: an inlier when it leaves the window, an outlier when
  // it is removed (never one outside the image).
  virtual void observationLeaves(const ActivePoint& p, const ActiveObservation& o) = 0;
  // A point that leaves the window with its information kept (marginalised, or at the end of the run).
  virtual void pointLeaves(const ActivePoint& p) = 0;
  // A keyframe at its final state, just before it is removed from the window.
  virtual void keyframeLeaves(Keyframe& kf) = 0;
};

struct WindowSetup {
  BackendOptions backend;
  FrontendOptions frontend;          // select (new candidates), trace (candidates), residual
  uint64_t seed = 0;                 // point selection seed (per keyframe: seed * 1000003 + kf_id)
  BundleAdjustmentConfig ba;         // its layout says whether the shutter is rolling
  bool smooth_motion = false;        // rolling shutter: a smooth-motion term with this information
  Mat6 smooth_motion_information = Mat6::Zero();
  DynamicMarginalizationOptions dynamic_marginalization;  // visual-inertial (imu.dynamic_marginalization)
};

class KeyframeWindow {
 public:
  // camera and solver must outlive the window; timing is the shutter's (its line delay the start when
  // the layout estimates it).
  KeyframeWindow(const WindowSetup& setup, const CameraModel& camera, const RowTiming& timing,
                 SolverBackend& solver);
  KeyframeWindow(const KeyframeWindow&) = delete;
  KeyframeWindow& operator=(const KeyframeWindow&) = delete;

  const KeyframeList& keyframes() const { return window_; }
  bool empty() const { return window_.empty(); }
  size_t size() const { return window_.size(); }
  Keyframe& newest() { return *window_.back(); }
  const Keyframe& newest() const { return *window_.back(); }
  bool hasSmoothMotion() const { return smooth_motion_ != nullptr; }
  int numActivePoints() const;

  // Keyframes to marginalise once the next keyframe is in (DSO's order: chosen before it joins).
  std::vector<Keyframe*> keyframesToMarginalize() const;
  // Adds a keyframe (its frame, time, exposure, pyramid and state set): gives it the next kf_id, makes
  // it the gauge if the window is empty, links its smooth-motion neighbours and adds an observation in
  // it to every active point. Returns it.
  Keyframe& insert(std::unique_ptr<Keyframe> kf);
  // Candidates of a new keyframe (the frontend's pixel selection on its pyramid).
  void createCandidates(Keyframe& kf);
  // Traces every keyframe's candidates into a tracked frame (its level-0 image).
  void traceCandidates(const CandidateFrame& target, const ImageLevel& target_level0);
  // Activates ready candidates into points around the newest keyframe (DSO's activatePointsMT) and
  // optimises their inverse depths against the window.
  void activateCandidates(Keyframe& newest);
  // The windowed bundle adjustment (kept in lastStats()); evaluate(): energies only.
  void optimize(int max_iterations);
  void evaluate();
  // The tracker's reference for frames after `newest`: its image and the active points seen in it.
  TrackingReference trackingReference(const Keyframe& newest) const;
  // After an optimisation: outlier and out-of-view observations removed, points without observations
  // dropped, points that leave (host flagged, out of the newest's view, too few observations left)
  // marginalised into the prior when well constrained, else dropped.
  void removeOutliersAndMarginalizePoints(Keyframe& newest, WindowSink& sink);
  // Removes a keyframe: observations into it logged and dropped, its points and candidates dropped,
  // its smooth-motion terms and keyframe priors added to the prior, its block marginalised.
  void marginalizeKeyframe(Keyframe* kf, WindowSink& sink);
  // End of the run: every point's inlier observations and every point with an inlier leave through the
  // sink; points and candidates are cleared, the keyframes stay (their states are the final ones).
  void releasePoints(WindowSink& sink);
  // The divergence tests after a keyframe's optimisation (docs/backend.md, "Divergence detection"):
  // a one-line reason, or empty. A solver failure that is not a divergence goes to *warning.
  std::string divergence(std::string* warning);

  const BundleAdjustmentStats& lastStats() const { return last_ba_; }
  // The marginalisation priors (one, or dynamic marginalisation's three once visual-inertial).
  const DynamicMarginalization& marginalization() const { return *prior_; }
  // The window's global states (line delay, and T_Wm_Wf and the time offset once visual-inertial) and
  // the row timing with the current line delay (updated by optimize() when it is estimated).
  GlobalStates& globals() { return globals_; }
  const GlobalStates& globals() const { return globals_; }
  const RowTiming& timing() const { return timing_; }

  // Visual-inertial runs: the inertial part whose terms leave with the keyframes (may be null).
  // The inertial state; its term joins the bundle adjuster's terms when it has one (before the
  // initialisation only with the gyroscope's rotations on).
  void setInertial(InertialState* inertial) {
    inertial_ = inertial;
    updateTerms();
  }
  // Tries the visual-inertial initialisation on the run's keyframe poses (InertialState::tryInitialize);
  // on success the bundle adjuster's terms gain the inertial term. Returns true when it succeeded now.
  bool initializeInertial(const std::vector<ViInitKeyframe>& keyframes);
  KeyframeList& mutableKeyframes() { return window_; }

 private:
  void updateTerms();
  void linkMotionNeighbours(Keyframe& kf);
  void marginalizeMotionTerms(const Keyframe* leaving);
  double medianIdepth() const;

  BackendOptions bo_;
  FrontendOptions fo_;
  uint64_t seed_ = 0;
  bool rolling_ = false;
  const CameraModel& camera_;
  RowTiming timing_;
  GlobalStates globals_;
  std::unique_ptr<CandidateTracer> tracer_;
  std::unique_ptr<BlockRunner> runner_;  // candidate tracing, one block per host keyframe
  std::unique_ptr<BundleAdjuster> ba_;
  std::unique_ptr<SmoothMotionTerm> smooth_motion_;  // rolling shutter with a smooth-motion prior, else null
  std::unique_ptr<DynamicMarginalization> prior_;  // its active() prior is the bundle adjuster's
  InertialState* inertial_ = nullptr;
  KeyframeList window_;
  int64_t next_kf_id_ = 0;
  int64_t next_point_id_ = 0;
  int64_t first_kf_id_ = -1;
  double min_act_dist_ = 2.0;
  double initial_median_idepth_ = 0.0;  // for the scale-collapse test
  BundleAdjustmentStats last_ba_;
};

// World point of an active point (fixed at its host row's time, rs_projection.h).
Vec3 pointInWorld(const ActivePoint& p, const RowTiming& timing, bool rolling);

}  // namespace rsvio
