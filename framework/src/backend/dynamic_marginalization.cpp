// Dynamic marginalisation for the scale (contract in rsvio/backend/dynamic_marginalization.h).
#include "rsvio/backend/dynamic_marginalization.h"

#include <cmath>

#include "rsvio/core/error.h"

namespace rsvio {

DynamicMarginalization::DynamicMarginalization(StateLayout layout, DynamicMarginalizationOptions o)
    : o_(o), priors_{MarginalizationPrior(layout), MarginalizationPrior(layout), MarginalizationPrior(layout)} {
  if (o_.enabled && !(o_.interval > 1.0)) throw Error("dynamic marginalisation: the interval factor must be > 1");
}

void DynamicMarginalization::setGlobals(GlobalStates* g) {
  for (auto& p : priors_) p.setGlobals(g);
}

void DynamicMarginalization::setLayout(const StateLayout& layout) {
  for (auto& p : priors_) p.setLayout(layout);
}

void DynamicMarginalization::marginalizeKeyframe(Keyframe* kf) {
  if (!o_.enabled) return active().marginalizeKeyframe(kf);
  for (auto& p : priors_) p.marginalizeKeyframe(kf);
}

void DynamicMarginalization::addTerm(const std::vector<Keyframe*>& kfs, const Eigen::MatrixXd& H_t,
                                     const Eigen::VectorXd& b_t, bool with_global) {
  if (!o_.enabled) return active().addTerm(kfs, H_t, b_t, with_global);
  for (auto& p : priors_) p.addTerm(kfs, H_t, b_t, with_global);
}

void DynamicMarginalization::addScaleFreeTerm(const std::vector<Keyframe*>& kfs, const Eigen::MatrixXd& H_t,
                                              const Eigen::VectorXd& b_t, bool project_scale, bool with_global) {
  if (!o_.enabled) return active().addScaleFreeTerm(kfs, H_t, b_t, project_scale, with_global);
  for (auto& p : priors_) p.addScaleFreeTerm(kfs, H_t, b_t, project_scale, with_global);
}

void DynamicMarginalization::addScaleTerm(const std::vector<Keyframe*>& kfs, const Eigen::MatrixXd& H_t,
                                          const Eigen::VectorXd& b_t, bool with_global) {
  active().addTerm(kfs, H_t, b_t, with_global);
  if (o_.enabled) priors_[kHalf].addTerm(kfs, H_t, b_t, with_global);
}

void DynamicMarginalization::start(double s, double t_s) {
  if (!o_.enabled || !(s > 0.0) || !std::isfinite(s)) return;
  started_ = true;
  s_mid_ = s;
  side_ = 1;
  events_.push_back(Record{t_s, s, s_mid_, Event::kStart});
}

DynamicMarginalization::Event DynamicMarginalization::update(double s, double t_s) {
  if (!started_ || !(s > 0.0) || !std::isfinite(s)) return Event::kNone;
  Event last = Event::kNone;
  const double d = o_.interval;
  // Left through a bound: the half next to it becomes current, the interval moves by one half-width.
  while (s > s_mid_ * d || s < s_mid_ / d) {
    const int out = s > s_mid_ ? 1 : -1;
    priors_[kCurrent] = priors_[kHalf];
    priors_[kHalf] = priors_[kVisual];
    s_mid_ = out > 0 ? s_mid_ * d : s_mid_ / d;
    side_ = side(s);
    ++switches_;
    last = Event::kSwitch;
    events_.push_back(Record{t_s, s, s_mid_, last});
  }
  if (last == Event::kNone && side(s) != side_) {  // crossed the centre: the half starts again
    priors_[kHalf] = priors_[kVisual];
    side_ = side(s);
    ++half_resets_;
    last = Event::kHalfReset;
    events_.push_back(Record{t_s, s, s_mid_, last});
  }
  return last;
}

const char* eventName(DynamicMarginalization::Event e) {
  switch (e) {
    case DynamicMarginalization::Event::kNone: return "none";
    case DynamicMarginalization::Event::kStart: return "start";
    case DynamicMarginalization::Event::kHalfReset: return "half_reset";
    case DynamicMarginalization::Event::kSwitch: return "switch";
  }
  return "?";
}

}  // namespace rsvio
