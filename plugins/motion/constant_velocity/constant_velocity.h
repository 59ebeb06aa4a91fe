// motion.constant_velocity: the tracker's guesses for a new frame from the last two frames, and a
// smooth-motion twist prior, as DSO does without an IMU (FullSystem::trackNewCoarse).
//
// Contract (rsvio/interfaces/motion_prior.h)
// - Poses T_c_w (camera from world, W_f), twists per second (translation; rotation) acting on the LEFT:
//   T_c_w(t) = exp(xi t) T_c_w^0 (paper eq. 6).
// - Velocity from the last two frames of the history: v = log(T_last T_prev^-1) / (t_last - t_prev)
//   (per second, so uneven frame intervals are handled), and the guesses for time t, best first:
//     1. constant velocity        exp(v s) T_last,      s = t - t_last
//     2. double motion            exp(2 v s) T_last     (a frame was dropped)
//     3. half motion              exp(v s / 2) T_last
//     4. no motion                T_last
//     5. no motion since the last keyframe (when it is not the last frame)
//     6. recovery: the constant-velocity guess turned by +-recovery_rotation_rad about every
//        combination of the camera axes (26 rotations, DSO's lastF_2_fh_tries), rotation about the
//        new camera's centre: exp((0; d)) * guess 1.
//   With one frame of history only 1 (= no motion) and its rotations; with none, nothing.
// - Twist prior (rolling shutter), information diag(info_trans x3, info_rot x3), one of two kinds:
//   "window" (default): smoothMotionInformation() hands the information to the back end's
//     smooth-motion term: the keyframe's twist tied to the OPTIMISED poses of its neighbour keyframes
//     (backend/smooth_motion_term.h), so twists and poses constrain each other;
//   "history": twistPrior() gives a fixed mean, the frame-to-frame velocity around the keyframe in the
//     tracked history (central difference of its neighbours, one-sided at the ends), set once.
//   Both return false when the weights are zero; twistPrior() also when the history has no neighbour.
#pragma once
#include <algorithm>
#include <cmath>
#include <vector>

#include "rsvio/core/time.h"
#include "rsvio/interfaces/motion_prior.h"

namespace rsvio {

struct ConstantVelocityOptions {
  bool recovery = true;                // add the zero-motion and rotated guesses
  double recovery_rotation_rad = 0.04;  // DSO: quaternion component 0.02, i.e. ~0.04 rad
  double twist_info_trans = 0.0;       // information of the twist prior, (s / unit)^2; 0 = no prior
  double twist_info_rot = 0.0;         // (s / rad)^2
  bool twist_prior_in_window = true;   // "window" (smooth-motion term) or "history" (fixed mean)
};

class ConstantVelocityPrior : public MotionPrior {
 public:
  explicit ConstantVelocityPrior(ConstantVelocityOptions o = {}) : o_(o) {}

  // Per-second velocity between two states (left twist taking a's pose to b's).
  static Vec6 velocity(const MotionState& a, const MotionState& b) {
    const double dt = nsToS(b.t_ns - a.t_ns);
    if (!(std::abs(dt) > 1e-12)) return Vec6::Zero();
    return (b.T_c_w * a.T_c_w.inverse()).log() / dt;
  }

  std::vector<SE3d> predict(const std::vector<MotionState>& history, int64_t t_ns) const override {
    std::vector<SE3d> out;
    if (history.empty()) return out;
    const MotionState& last = history.back();
    SE3d main = last.T_c_w;
    if (history.size() >= 2) {
      const Vec6 v = velocity(history[history.size() - 2], last);
      const double s = nsToS(t_ns - last.t_ns);
      main = SE3d::exp(v * s) * last.T_c_w;
      out.push_back(main);
      if (o_.recovery) {
        out.push_back(SE3d::exp(v * (2.0 * s)) * last.T_c_w);
        out.push_back(SE3d::exp(v * (0.5 * s)) * last.T_c_w);
        out.push_back(last.T_c_w);
      }
    } else {
      out.push_back(main);
    }
    if (!o_.recovery) return out;
    // Last keyframe in the history, if it is not the last frame.
    for (size_t i = history.size() - 1; i-- > 0;) {
      if (history[i].is_keyframe) {
        out.push_back(history[i].T_c_w);
        break;
      }
    }
    const double d = o_.recovery_rotation_rad;
    for (int x = -1; x <= 1; ++x)
      for (int y = -1; y <= 1; ++y)
        for (int z = -1; z <= 1; ++z) {
          if (x == 0 && y == 0 && z == 0) continue;
          Vec6 xi = Vec6::Zero();
          xi.tail<3>() = Vec3(x, y, z) * d;
          out.push_back(SE3d::exp(xi) * main);
        }
    return out;
  }

  bool twistPrior(const std::vector<MotionState>& history, const MotionState& keyframe,
                  TwistPrior* prior) const override {
    if (o_.twist_prior_in_window) return false;
    if (!(o_.twist_info_trans > 0.0 || o_.twist_info_rot > 0.0) || history.size() < 2) return false;
    // The keyframe's place in the time-ordered history.
    const auto it = std::lower_bound(history.begin(), history.end(), keyframe.t_ns,
                                     [](const MotionState& s, int64_t t) { return s.t_ns < t; });
    const MotionState* prev = nullptr;
    const MotionState* next = nullptr;
    if (it != history.begin()) prev = &*(it - 1);
    auto after = it;
    if (after != history.end() && after->t_ns == keyframe.t_ns) ++after;
    if (after != history.end()) next = &*after;
    Vec6 mean;
    if (prev && next) {
      mean = velocity(*prev, *next);
    } else if (prev) {
      mean = velocity(*prev, keyframe);
    } else if (next) {
      mean = velocity(keyframe, *next);
    } else {
      return false;
    }
    if (prior) {
      prior->mean = mean;
      prior->information.setZero();
      prior->information.diagonal() << Vec3::Constant(o_.twist_info_trans), Vec3::Constant(o_.twist_info_rot);
    }
    return true;
  }

  bool smoothMotionInformation(Mat6* information) const override {
    if (!o_.twist_prior_in_window || !(o_.twist_info_trans > 0.0 || o_.twist_info_rot > 0.0)) return false;
    if (information) {
      information->setZero();
      information->diagonal() << Vec3::Constant(o_.twist_info_trans), Vec3::Constant(o_.twist_info_rot);
    }
    return true;
  }

  const ConstantVelocityOptions& options() const { return o_; }

 private:
  ConstantVelocityOptions o_;
};

}  // namespace rsvio
