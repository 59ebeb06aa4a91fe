// Keyframe creation and marginalisation choices (contract in rsvio/backend/keyframe_policy.h).
#include "rsvio/backend/keyframe_policy.h"

#include <cmath>

namespace rsvio {

bool needKeyframe(const BackendOptions& o, const KeyframeCue& c, std::string* reason) {
  auto say = [&](const char* r) {
    if (reason) *reason = r;
    return true;
  };
  const double wh = std::max(1, c.width + c.height);
  const double scale = c.keyframes >= o.kf_start_keyframes ? o.kf_flow_scale : 1.0;
  const double score = scale * (o.kf_weight_t * c.flow_t_px + o.kf_weight_rt * c.flow_rt_px) / wh;
  if (score + o.kf_weight_affine * std::abs(c.log_brightness_ratio) > 1.0) {
    if (score > 1.0) return say("flow");
    return say(score > 0.0 ? "flow and brightness" : "brightness");
  }
  if (std::isfinite(c.first_rmse) && c.first_rmse > 0.0 && c.rmse > o.kf_rmse_factor * c.first_rmse) return say("rmse");
  if (o.kf_max_interval_s > 0.0 && c.seconds_since_keyframe >= o.kf_max_interval_s) return say("interval");
  return false;
}

double logBrightnessRatio(const AffineBrightness& from, double from_exposure_ms, const AffineBrightness& to,
                          double to_exposure_ms) {
  const double exp_ratio = (from_exposure_ms > 0.0 && to_exposure_ms > 0.0) ? to_exposure_ms / from_exposure_ms : 1.0;
  return std::log(exp_ratio) + to.a - from.a;
}

std::vector<Keyframe*> keyframesToMarginalize(const KeyframeList& window, const BackendOptions& o, int64_t first_kf_id) {
  std::vector<Keyframe*> out;
  if (window.empty()) return out;
  const Keyframe& latest = *window.back();
  int flagged = 0;
  const int n = static_cast<int>(window.size());
  for (const auto& kf : window) kf->flagged_for_marg = false;
  for (const auto& kf : window) {
    const int in = static_cast<int>(kf->points.size()) + static_cast<int>(kf->candidates.size());
    const int all = in + kf->points_out;
    const double lr = logBrightnessRatio(latest.state.affine, latest.exposure_ms, kf->state.affine, kf->exposure_ms);
    if ((in < o.min_points_remaining * all || std::abs(lr) > o.max_log_affine) && n - flagged > o.min_keyframes) {
      kf->flagged_for_marg = true;
      ++flagged;
    }
  }
  if (n - flagged >= o.max_keyframes) {
    const Vec3 c_latest = latest.state.T_c_w.inverse().translation();
    Keyframe* best = nullptr;
    double best_score = -1.0;
    for (const auto& kf : window) {
      if (kf.get() == &latest || kf->kf_id == first_kf_id || kf->flagged_for_marg) continue;
      const Vec3 ci = kf->state.T_c_w.inverse().translation();
      double sum = 0.0;
      for (const auto& other : window) {
        if (other.get() == kf.get()) continue;
        sum += 1.0 / ((other->state.T_c_w.inverse().translation() - ci).norm() + 1e-5);
      }
      const double score = std::sqrt((c_latest - ci).norm()) * sum;
      if (score > best_score) {
        best_score = score;
        best = kf.get();
      }
    }
    if (!best) {  // only the first keyframe is left to choose: take it rather than overflow
      for (const auto& kf : window)
        if (kf.get() != &latest && !kf->flagged_for_marg) {
          best = kf.get();
          break;
        }
    }
    if (best) best->flagged_for_marg = true;
  }
  for (const auto& kf : window)
    if (kf->flagged_for_marg) out.push_back(kf.get());
  return out;
}

}  // namespace rsvio
