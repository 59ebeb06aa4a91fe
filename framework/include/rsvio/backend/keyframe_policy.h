// Keyframe management (DSO, Engel et al. 2018, sec. 3.1 "Keyframe creation" and "Keyframe
// marginalization"): when a tracked frame becomes a keyframe, and which keyframes leave the window.
//
// Contract
// - needKeyframe(): a new keyframe when
//     s (kf_weight_t * flow_t + kf_weight_rt * flow_rt) / (width + height) + kf_weight_affine |log a| > 1
//   with s = kf_flow_scale once the run has kf_start_keyframes keyframes and s = 1 before (DSO's
//   setting_kfGlobalWeight, s = 1, throughout; gs_vo.json's s = 0.5 after 7 keyframes: docs/performance.md,
//   "Fewer keyframes")
//   (flow_t, flow_rt: RMS pixel shift of the reference points with the translation only / the full
//   relative motion, FrameTracker's indicators; a: the brightness ratio to the reference keyframe),
//   or when the tracking RMSE exceeds kf_rmse_factor x the first RMSE after the reference keyframe
//   (DSO's "2 x firstCoarseRMSE"), or when kf_max_interval_s > 0 has passed.
// - keyframesToMarginalize(window): called before a new keyframe joins (DSO's order). Flags every
//   keyframe that keeps fewer than min_points_remaining of its points (active + candidates vs. points
//   that left) or whose brightness ratio to the newest keyframe exceeds exp(max_log_affine), as long
//   as more than min_keyframes stay; then, if the window would still be full (max_keyframes), the
//   keyframe with the largest distance score  sqrt(d(i, newest)) * sum_j 1 / (d(i, j) + 1e-5), d the
//   Euclidean distance of camera centres, j over the other keyframes; candidates are all but the newest
//   keyframe and the first keyframe of the run (DSO keeps that one to the point test).
#pragma once
#include <string>
#include <vector>

#include "rsvio/backend/backend_options.h"
#include "rsvio/backend/window.h"

namespace rsvio {

struct KeyframeCue {
  double flow_t_px = 0.0;
  double flow_rt_px = 0.0;
  double log_brightness_ratio = 0.0;  // log(exposure ratio * exp(a_frame - a_reference))
  double rmse = 0.0;
  double first_rmse = 0.0;            // RMSE of the first frame tracked against the reference (NaN: none)
  double seconds_since_keyframe = 0.0;
  int64_t keyframes = 0;              // keyframes the run has made so far
  int width = 0, height = 0;
};

// Returns true and the reason ("flow", "brightness", "rmse", "interval") when a keyframe is needed.
bool needKeyframe(const BackendOptions& o, const KeyframeCue& cue, std::string* reason = nullptr);

// log of the brightness transfer from `from` to `to`: log(exposure ratio) + a_to - a_from (DSO's
// AffLight::fromToVecExposure()[0]); exposures in ms, NaN when unknown (ratio 1).
double logBrightnessRatio(const AffineBrightness& from, double from_exposure_ms, const AffineBrightness& to,
                          double to_exposure_ms);

// Keyframes to marginalise before a new keyframe joins (see the contract), oldest first.
// first_kf_id: kf_id of the run's first keyframe.
std::vector<Keyframe*> keyframesToMarginalize(const KeyframeList& window, const BackendOptions& o, int64_t first_kf_id);

}  // namespace rsvio
