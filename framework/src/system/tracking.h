// Tracking of rsvio::Odometry: every frame against the newest keyframe (frontend/frame_tracker.h),
// from the motion priors' guesses, and the motion history those priors predict from.
//
// Owns
// - the frame tracker and its reference (the newest keyframe's image and the active points seen in
//   it, set by setReference());
// - the motion history: the last 32 tracked frames (MotionState, oldest first), a keyframe's entry
//   with its optimised pose;
// - the frames lost in a row, the frames a twist retry saved, and the first tracking RMSE since the
//   reference was set (the keyframe policy's RMSE cue).
// It uses, not owns, the configured motion priors (motion.* plugins).
//
// Invariants
// - The history is in time order, holds at most 32 frames, and from its third frame on each entry
//   carries the frame-to-frame twist of its last two (velocityEstimate() when it was added).
// - The first RMSE is NaN from setReference() until a frame tracks against that reference.
// - The lost counter is 0 after a tracked frame.
#pragma once
#include <cmath>
#include <memory>
#include <vector>

#include "rsvio/backend/window.h"
#include "rsvio/frontend/frame_tracker.h"
#include "rsvio/interfaces/camera.h"
#include "rsvio/interfaces/motion_prior.h"

namespace rsvio {

class Tracking {
 public:
  // camera, timing and the motion priors must outlive the tracking.
  Tracking(const TrackerOptions& options, const CameraModel& camera, const RowTiming& timing,
           std::vector<const MotionPrior*> motion);

  // Tracks a frame from guesses(); *ok: tracked with a finite pose (else the lost counter grows).
  // Rolling shutter: a frame lost with info.twist is tracked again, at most TrackerOptions::twist_retries
  // times, from the pose the last attempt reached and with the twist's rotation rotationRateAt(t, that
  // pose) (translation kept). A frame whose rotation rate changed suddenly is otherwise lost, as the
  // fast preset's were within 2 s (docs/rolling_shutter.md, "Twist retries"). A frame the tracker kept
  // although poorly explained (TrackResult::poorly_explained) is retried the same way, and a retry that
  // explains more replaces it.
  // A tracked frame is tracked again TrackerOptions::twist_refinements times (rolling shutter, two
  // frames of history, info.twist_measured false), from its pose and with the rotation
  // rotationRateAt(t, that pose): the predicted rotation is the last interval's mean rate, 75 ms old at
  // the frame, and its error turns into pose error (docs/rolling_shutter.md, "Twist refinement").
  // With the same two conditions and TrackerOptions::rotation_rate_sigma > 0 (the default) the tracker
  // estimates the twist's rotation with the pose (info.estimate_rotation_rate; TrackResult::twist,
  // rate_estimated), the refinements' default being 0 (docs/rolling_shutter.md, "The rotation rate
  // estimated by the tracker").
  TrackResult track(const ImagePyramid& pyr, const TrackingFrame& info, bool* ok);
  // Tracks a frame from given guesses (frames of the monocular start): the tracker accepts an Ok result
  // (FrameTracker::accept); the lost counter and the motion history are untouched.
  TrackResult trackFrom(const ImagePyramid& pyr, const TrackingFrame& info, const std::vector<SE3d>& guesses);
  void setReference(const TrackingReference& reference);
  // A new line delay (estimated online); takes effect with the next setReference().
  void setTiming(const RowTiming& timing);
  void resetFirstRmse() { first_rmse_ = std::nan(""); }
  int lostInRow() const { return lost_in_row_; }
  long twistRescues() const { return twist_rescues_; }  // frames a twist retry tracked or explained better
  double firstRmse() const { return first_rmse_; }

  // Motion history.
  void pushHistory(int64_t t_ns, const SE3d& T_c_w, bool is_keyframe);
  void keyframeOptimised(int64_t t_ns, const SE3d& T_c_w);  // the keyframe's entry takes its optimised pose
  // The history entry of time t_ns (null: none), e.g. for the inertial state to fill its VIO fields.
  MotionState* historyAt(int64_t t_ns);
  std::vector<SE3d> guesses(int64_t t_ns) const;             // every motion prior's, else the last pose
  Vec6 velocityEstimate() const;  // per second, from the last two tracked frames (0 without)
  // Rolling shutter: a new frame's twist (see tracking.cpp); newest: the newest keyframe, or nullptr.
  Vec6 frameTwistGuess(const Keyframe* newest) const;
  // Rotation rate (the twist's rotation part, per second) at time t_ns: the last two frame intervals'
  // mean rates, each at its interval's middle, extrapolated linearly to t_ns; with `last` given, the
  // newest interval is from the newest history entry to (t_ns, *last). Fewer than 2 intervals: the
  // last interval's rate (0 without).
  Vec3 rotationRateAt(int64_t t_ns, const SE3d* last = nullptr) const;
  // The first motion prior's fixed-mean twist prior for a new keyframe, if any has one.
  bool twistPrior(const MotionState& keyframe, TwistPrior* prior) const;

 private:
  std::unique_ptr<FrameTracker> tracker_;
  std::vector<const MotionPrior*> motion_;
  std::vector<MotionState> history_;
  RowTiming timing_;
  int twist_retries_ = 0;
  int twist_refinements_ = 0;
  int lost_in_row_ = 0;
  long twist_rescues_ = 0;
  double first_rmse_ = std::nan("");
};

}  // namespace rsvio
