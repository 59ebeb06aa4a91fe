// Tracking (contract in tracking.h): the tracker's calls, the lost counter and the motion history.
#include "tracking.h"

#include "rsvio/core/time.h"

namespace rsvio {

Tracking::Tracking(const TrackerOptions& options, const CameraModel& camera, const RowTiming& timing,
                   std::vector<const MotionPrior*> motion)
    : tracker_(std::make_unique<FrameTracker>(options, camera, timing)),
      motion_(std::move(motion)),
      timing_(timing),
      twist_retries_(options.twist_retries),
      twist_refinements_(options.twist_refinements) {}

TrackResult Tracking::track(const ImagePyramid& pyr, const TrackingFrame& info_in, bool* ok) {
  auto good = [](const TrackResult& r) { return r.ok() && r.T_c_w.translation().allFinite(); };
  TrackingFrame info = info_in;
  const bool rolling_unmeasured = timing_.dtDv() != 0.0 && !info.twist_measured && history_.size() >= 2;
  info.estimate_rotation_rate = rolling_unmeasured && tracker_->options().rotation_rate_sigma > 0.0;
  if (rolling_unmeasured && tracker_->options().twist_refresh_levels > 0)
    info.rotation_rate_of_pose = [this, t = info.t_ns](const SE3d& T) { return rotationRateAt(t, &T); };
  const std::vector<SE3d> g = guesses(info.t_ns);
  TrackResult r = tracker_->track(pyr, info, g);
  *ok = good(r);
  // Twist retries (rolling shutter, see tracking.h): the lost attempt's pose, rotation-dominated, is
  // mostly right where the predicted twist lagged a sudden change of the rotation rate (its readout
  // shear is then missing from the model); the rate through that pose, extrapolated to the frame's
  // time, is the better twist, and the pose the better first guess. A frame kept although poorly
  // explained (TrackResult::poorly_explained) is retried the same way; a retry replaces it when it
  // explains more.
  for (int k = 0; (!*ok || r.poorly_explained) && timing_.dtDv() != 0.0 && k < twist_retries_; ++k) {
    const SE3d T = r.T_c_w;
    info.twist.tail<3>() = rotationRateAt(info.t_ns, &T);
    std::vector<SE3d> gk{T};
    gk.insert(gk.end(), g.begin(), g.end());
    TrackResult rk = tracker_->track(pyr, info, gk);
    if (*ok && !(good(rk) && rk.explained_ratio > r.explained_ratio)) break;
    if (good(rk)) ++twist_rescues_;
    r = std::move(rk);
    *ok = good(r);
  }
  if (!*ok) {
    ++lost_in_row_;
    return r;
  }
  // Twist refinement (rolling shutter, see tracking.h): the predicted rotation lags; the rate through
  // the pose just found, extrapolated to the frame's time, is nearer the truth, and the frame is tracked
  // again with it from that pose. A refinement that does not track keeps the result before it. Needs two
  // frames of history (the rate through one interval would lag as the prediction does).
  const bool refine = rolling_unmeasured;
  for (int k = 0; refine && k < twist_refinements_; ++k) {
    const SE3d T = r.T_c_w;
    info.twist.tail<3>() = rotationRateAt(info.t_ns, &T);
    const TrackResult rk = tracker_->track(pyr, info, {T});
    if (!good(rk)) break;
    r = rk;
  }
  lost_in_row_ = 0;
  if (std::isnan(first_rmse_)) first_rmse_ = r.rmse;
  tracker_->accept(r);  // once, the result kept: retries and refinements above are not frames
  return r;
}

TrackResult Tracking::trackFrom(const ImagePyramid& pyr, const TrackingFrame& info, const std::vector<SE3d>& guesses) {
  TrackResult r = tracker_->track(pyr, info, guesses);
  tracker_->accept(r);  // Ok only
  return r;
}

void Tracking::setTiming(const RowTiming& timing) {
  tracker_->setTiming(timing);
  timing_ = timing;
}

void Tracking::setReference(const TrackingReference& reference) {
  tracker_->setReference(reference);
  first_rmse_ = std::nan("");
}

Vec6 Tracking::velocityEstimate() const {
  if (history_.size() < 2) return Vec6::Zero();
  const MotionState& a = history_[history_.size() - 2];
  const MotionState& b = history_.back();
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
Vec6 Tracking::frameTwistGuess(const Keyframe* newest) const {
  Vec6 xi = velocityEstimate();
  if (newest) xi.head<3>() = newest->state.twist.head<3>();
  return xi;
}

Vec3 Tracking::rotationRateAt(int64_t t_ns, const SE3d* last) const {
  std::vector<std::pair<int64_t, const SE3d*>> h;
  for (size_t i = history_.size() >= 3 ? history_.size() - 3 : 0; i < history_.size(); ++i)
    h.emplace_back(history_[i].t_ns, &history_[i].T_c_w);
  if (last) h.emplace_back(t_ns, last);
  if (h.size() > 3) h.erase(h.begin());
  if (h.size() < 2) return Vec3::Zero();
  auto rate = [&](size_t i) {  // interval (i-1, i): mean rate and middle time (s)
    const double dt = nsToS(h[i].first - h[i - 1].first);
    return std::make_pair(Vec3((*h[i].second * h[i - 1].second->inverse()).so3().log() / dt),
                          0.5 * nsToS(h[i].first + h[i - 1].first - 2 * h.front().first));
  };
  const auto [w1, c1] = rate(h.size() - 1);
  if (h.size() < 3) return w1;
  const auto [w0, c0] = rate(h.size() - 2);
  const double tt = nsToS(t_ns - h.front().first);
  return w1 + (w1 - w0) * ((tt - c1) / (c1 - c0));
}

void Tracking::pushHistory(int64_t t_ns, const SE3d& T_c_w, bool is_keyframe) {
  MotionState s;
  s.t_ns = t_ns;
  s.T_c_w = T_c_w;
  s.is_keyframe = is_keyframe;
  history_.push_back(s);
  if (history_.size() > 2) history_.back().twist = velocityEstimate();
  constexpr size_t kHistory = 32;
  if (history_.size() > kHistory) history_.erase(history_.begin(), history_.begin() + (history_.size() - kHistory));
}

MotionState* Tracking::historyAt(int64_t t_ns) {
  for (auto it = history_.rbegin(); it != history_.rend(); ++it)
    if (it->t_ns == t_ns) return &*it;
  return nullptr;
}

void Tracking::keyframeOptimised(int64_t t_ns, const SE3d& T_c_w) {
  for (MotionState& s : history_)
    if (s.t_ns == t_ns) {
      s.T_c_w = T_c_w;
      s.is_keyframe = true;
    }
}

std::vector<SE3d> Tracking::guesses(int64_t t_ns) const {
  std::vector<SE3d> out;
  for (const MotionPrior* m : motion_) {
    const std::vector<SE3d> g = m->predict(history_, t_ns);
    out.insert(out.end(), g.begin(), g.end());
  }
  if (out.empty() && !history_.empty()) out.push_back(history_.back().T_c_w);
  return out;
}

bool Tracking::twistPrior(const MotionState& keyframe, TwistPrior* prior) const {
  for (const MotionPrior* m : motion_) {
    TwistPrior tp;  // a fresh one per prior: one that declines leaves nothing behind
    if (m->twistPrior(history_, keyframe, &tp)) {
      *prior = tp;
      return true;
    }
  }
  return false;
}

}  // namespace rsvio
