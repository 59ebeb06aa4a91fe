// Dynamic marginalisation for the scale (VI-DSO: von Stumberg, Usenko, Cremers, ICRA 2018, sec. IV-D;
// the rolling-shutter paper, sec. IV-D: "a second version of the marginalization Hessian that only
// contains newer IMU factors"). docs/vio.md, "Dynamic marginalisation", explains it with a figure.
//
// Why: a marginalised term keeps the linearisation it had when it left (first-estimate Jacobians,
// marginalization.h). For the monocular scale that is a bad approximation right after the
// visual-inertial initialisation: the scale moves by tens of percent while the IMU makes it observable,
// and the IMU factors marginalised at the old scale keep pulling it back with Jacobians from there.
//
// What: three priors over the same keyframes and global block, fed with the same terms as they leave:
// - visual: the terms that do not depend on the metric scale (marginalised points, smooth-motion terms,
//   keyframe priors): addTerm / addScaleFreeTerm;
// - current: everything, also the scale-dependent terms (IMU factors and the twist energy, which
//   divides the IMU's translation by the scale): addScaleTerm. The bundle adjuster uses this one;
// - half: everything since the scale estimate entered the half of the interval it is in now.
// The interval is [s_mid / d, s_mid * d] around s_mid, the scale at start() (the initialisation), with
// the halves [s_mid / d, s_mid] and [s_mid, s_mid * d]. update(s) after each optimisation:
// - s left the interval through the bound s_mid * d (or s_mid / d): current <- half (whose terms were all
//   linearised in the half next to that bound), half <- visual, s_mid <- that bound, so the half that
//   the new current's terms come from is the lower (upper) half of the new interval; repeated while s
//   is still outside (a jump over several intervals ends with current = visual);
// - s crossed s_mid into the other half: half <- visual.
// Linearisation points are shared by the three (a keyframe's or the global block's is frozen once,
// when the first of them gives it a block: Keyframe::in_prior, GlobalStates::in_prior), so switching
// priors never moves the point a prior's quadratic is expressed at.
//
// With enabled = false there is one prior (current), and every add goes to it: what a run without
// dynamic marginalisation did before.
#pragma once
#include <string>
#include <vector>

#include "rsvio/backend/marginalization.h"

namespace rsvio {

struct DynamicMarginalizationOptions {
  bool enabled = false;
  double interval = 1.1;  // d > 1: the factor between s_mid and the bounds of the interval
};

class DynamicMarginalization {
 public:
  enum class Event { kNone, kStart, kHalfReset, kSwitch };
  struct Record {
    double t_s = 0.0;     // when update() saw it (caller's time)
    double scale = 0.0;   // the scale estimate then
    double s_mid = 0.0;   // the interval's centre after the event
    Event event = Event::kNone;  // kStart, kHalfReset or kSwitch
  };

  explicit DynamicMarginalization(StateLayout layout = {}, DynamicMarginalizationOptions o = {});

  const DynamicMarginalizationOptions& options() const { return o_; }
  // The prior the bundle adjuster uses (current).
  MarginalizationPrior& active() { return priors_[kCurrent]; }
  const MarginalizationPrior& active() const { return priors_[kCurrent]; }
  const MarginalizationPrior& visual() const { return priors_[kVisual]; }
  const MarginalizationPrior& half() const { return priors_[kHalf]; }
  const StateLayout& layout() const { return active().layout(); }

  // As MarginalizationPrior's, for every prior.
  void setGlobals(GlobalStates* g);
  void setLayout(const StateLayout& layout);
  void marginalizeKeyframe(Keyframe* kf);

  // A term that does not depend on the scale: into every prior (MarginalizationPrior::addTerm).
  void addTerm(const std::vector<Keyframe*>& kfs, const Eigen::MatrixXd& H_t, const Eigen::VectorXd& b_t,
               bool with_global = false);
  void addScaleFreeTerm(const std::vector<Keyframe*>& kfs, const Eigen::MatrixXd& H_t, const Eigen::VectorXd& b_t,
                        bool project_scale, bool with_global = false);
  // A term that depends on the scale (IMU factor, twist energy): into current and half, not visual.
  void addScaleTerm(const std::vector<Keyframe*>& kfs, const Eigen::MatrixXd& H_t, const Eigen::VectorXd& b_t,
                    bool with_global);

  // The scale becomes observable (visual-inertial initialisation) at scale s > 0: s_mid = s.
  void start(double s, double t_s);
  bool started() const { return started_; }
  double centre() const { return s_mid_; }
  // After an optimisation, with the scale estimate s: switches priors as in the contract. Returns the
  // last event (kNone when nothing changed, or when disabled or not started). Every event is recorded.
  Event update(double s, double t_s);
  const std::vector<Record>& events() const { return events_; }
  int numSwitches() const { return switches_; }
  int numHalfResets() const { return half_resets_; }

 private:
  static constexpr int kVisual = 0, kCurrent = 1, kHalf = 2;
  int side(double s) const { return s >= s_mid_ ? 1 : -1; }  // the half s is in
  DynamicMarginalizationOptions o_;
  MarginalizationPrior priors_[3];
  bool started_ = false;
  double s_mid_ = 0.0;
  int side_ = 1;
  int switches_ = 0, half_resets_ = 0;
  std::vector<Record> events_;
};

const char* eventName(DynamicMarginalization::Event e);

}  // namespace rsvio
