// Interface of motion.* plugins: priors on motion, for the tracker (a guess of the next pose) and for
// the back end (a prior on a keyframe's twist).
//
// Contract
// - Poses are camera-from-world T_c_w in the estimator's world (W_f: free scale until the IMU fixes it).
// - Twists are per second, (translation; rotation), acting on the left: T_c_w(t) = exp(xi t) T_c_w^0
//   (paper eq. 6), t relative to the frame timestamp (row y0).
// - predict() returns guesses for a new frame, best first; the tracker tries them in order (the
//   first is the prior's prediction, further ones are recovery guesses).
// - IMU samples arrive through addImu() in time order on the IMU clock; a prior that ignores the IMU
//   leaves addImu empty.
// - twistPrior(): a prior with a fixed mean on a keyframe's twist, set when the keyframe is made
//   (paper eq. 33 from the IMU, or the tracked history); returns false if this prior has no opinion.
// - smoothMotionInformation(): the information of the smooth-motion prior inside the window
//   optimisation (backend/smooth_motion_term.h: the twist tied to the optimised poses of its
//   neighbour keyframes, DSO-RS); returns false if this prior has none.
// - twistEnergySigma(): the metric standard deviations of the IMU twist energy inside the window
//   optimisation (paper eq. 33's Sigma; backend/inertial_term.h), translation in m/s and rotation in
//   rad/s; returns false if this prior has none. Used by visual-inertial runs with a rolling shutter.
#pragma once
#include <vector>

#include "rsvio/core/types.h"
#include "rsvio/lie/se3.h"
#include "rsvio/plugin/plugin.h"

namespace rsvio {

// What the estimator knows about a past frame (never ground truth).
struct MotionState {
  int64_t t_ns = 0;
  SE3d T_c_w;
  Vec6 twist = Vec6::Zero();       // per second
  bool is_keyframe = false;
  // VIO state when available (metric world W_m, body = IMU).
  bool has_inertial = false;
  SE3d T_wm_wf;                    // scale is carried separately
  double scale = 1.0;              // metres per W_f unit
  Vec3 v_wm = Vec3::Zero();        // IMU velocity in W_m, m/s
  Vec3 bias_gyro = Vec3::Zero();
  Vec3 bias_accel = Vec3::Zero();
};

struct TwistPrior {
  Vec6 mean = Vec6::Zero();         // per second
  Mat6 information = Mat6::Zero();  // inverse covariance
};

class MotionPrior : public PluginBase {
 public:
  static constexpr PluginKind kKind = PluginKind::Motion;

  virtual void setSensors(const SensorSetup& /*sensors*/) {}
  virtual void addImu(const ImuSample& /*sample*/) {}
  virtual std::vector<SE3d> predict(const std::vector<MotionState>& history, int64_t t_ns) const = 0;
  virtual bool twistPrior(const std::vector<MotionState>& /*history*/, const MotionState& /*keyframe*/,
                          TwistPrior* /*prior*/) const {
    return false;
  }
  virtual bool smoothMotionInformation(Mat6* /*information*/) const { return false; }
  virtual bool twistEnergySigma(double* /*sigma_trans_m_s*/, double* /*sigma_rot_rad_s*/) const { return false; }
};

}  // namespace rsvio
