// motion.imu: the tracker's guess for a new frame by integrating the IMU from the last state, and the
// IMU twist prior of a keyframe (paper eqs. 22-33).
//
// Contract (rsvio/interfaces/motion_prior.h)
// - Poses T_c_w are T_Cf_Wf (camera from the free-scale world W_f); twists per second, (translation;
//   rotation), acting on the LEFT: T_c_w(t) = exp(xi t) T_c_w^0 (paper eq. 6).
// - IMU samples arrive through addImu() on the IMU clock; camera times convert with
//   t_imu = t_cam + time_offset, the calibrated offset (CameraCalibration::time_offset_s).
//   T_Cm_I = T_C_B from the calibration (CameraCalibration::T_B_C inverted).
// - predict(history, t): with an inertial state in the last history entry (has_inertial) and IMU data
//   covering [t_last, t], the metric IMU state of the last frame (imu_frames.h: T_Wm_I from T_c_w,
//   T_Wm_Wf = (scale, rotation of T_wm_wf) and T_Cm_I) is propagated with the preintegrated IMU at the
//   state's biases (eqs. 13-15) and mapped back to T_Cf_Wf. Without an inertial state (before the
//   visual-inertial initialisation) or without IMU coverage it falls back to constant velocity from
//   the last two frames (one frame: its pose). Before the initialisation, with `gyro_rotation_guess`
//   and IMU coverage, the first guess is that constant-velocity guess's camera centre with the
//   rotation the gyroscope integrates from the last frame (bias 0: it is not estimated yet):
//       R_Wf_C(t) = R_Wf_C(t_last) R_C_I dR_I(t_last -> t) R_I_C.
//   With `recovery`, the constant-velocity guess (when an IMU guess came first) and "no motion" follow
//   as further guesses.
// - twistPrior(history, keyframe): needs keyframe.has_inertial and IMU data at the keyframe's time;
//   mean = eq. 32 from the gyroscope reading interpolated at the keyframe's time, the keyframe's
//   velocity, gyro bias, pose and scale-gravity transform; information diagonal (the paper's manually
//   chosen Sigma of eq. 33) from metric standard deviations:
//       translation: (scale / twist_sigma_trans_m_s)^2 per (W_f unit/s)^2,
//       rotation:    (1 / twist_sigma_rot_rad_s)^2.
//   Returns false when it has no opinion (no inertial state, no IMU data there).
#pragma once
#include <algorithm>
#include <cmath>
#include <vector>

#include "rsvio/core/time.h"
#include "rsvio/imu/imu_buffer.h"
#include "rsvio/imu/imu_factor.h"
#include "rsvio/imu/imu_frames.h"
#include "rsvio/imu/preintegration.h"
#include "rsvio/imu/twist_prior.h"
#include "rsvio/interfaces/motion_prior.h"

namespace rsvio {

struct ImuMotionOptions {
  double twist_sigma_trans_m_s = 0.1;    // std of the IMU twist prior's translation, m/s
  double twist_sigma_rot_rad_s = 0.02;   // std of its rotation, rad/s (gyro noise + bias uncertainty)
  double buffer_s = 20.0;                // IMU history kept (covers the keyframe window's twist priors)
  double max_extrapolation_ms = 5.0;     // a camera stamp this far past the last IMU sample holds it
  bool recovery = true;                  // append constant-velocity and no-motion guesses
  // Before the visual-inertial initialisation: the first guess's rotation from the gyroscope (the
  // constant-velocity guess's rotation is 1-3.5 deg off at the Table I motions' 500 deg/s^2). Off: it
  // prevented none of rs_vio's early losses there (docs/vio.md, 2026-12-05).
  bool gyro_rotation_guess = false;
  // The window's smooth-motion prior on the rolling-shutter twists (backend/smooth_motion_term.h, as
  // motion.constant_velocity's twist_info_*), non-metric: per (W_f unit / s)^2 and (s / rad)^2. It holds
  // the twists before the visual-inertial initialisation, when the IMU twist energy has no scale yet,
  // and stays beside it after. Inert with a global shutter. 0 and 0: none.
  double smooth_twist_info_trans = 1e5;
  double smooth_twist_info_rot = 1e5;
};

class ImuMotionPrior : public MotionPrior {
 public:
  explicit ImuMotionPrior(ImuMotionOptions o = {})
      : o_(o), buffer_(static_cast<int64_t>(std::llround(o.max_extrapolation_ms * 1e6))) {}

  void setSensors(const SensorSetup& sensors) override {
    has_imu_ = sensors.has_imu;
    noise_ = sensors.imu;
    T_cm_i_ = cameraFromImu(sensors.camera.T_B_C);
    time_offset_s_ = sensors.camera.time_offset_s;
  }

  void addImu(const ImuSample& s) override {
    buffer_.add(s);
    buffer_.dropBefore(s.t_ns - static_cast<int64_t>(std::llround(o_.buffer_s * 1e9)));
  }

  std::vector<SE3d> predict(const std::vector<MotionState>& history, int64_t t_ns) const override {
    std::vector<SE3d> out;
    if (history.empty()) return out;
    const MotionState& last = history.back();
    const SE3d cv = constantVelocityGuess(history, t_ns);
    SE3d imu_guess;
    const bool have_imu_guess = imuGuess(last, t_ns, &imu_guess) ||
                                (o_.gyro_rotation_guess && !last.has_inertial && gyroGuess(last, cv, t_ns, &imu_guess));
    if (have_imu_guess) out.push_back(imu_guess);
    out.push_back(cv);
    if (!o_.recovery) return {out.front()};
    if (history.size() >= 2) out.push_back(last.T_c_w);
    return out;
  }

  bool twistPrior(const std::vector<MotionState>& /*history*/, const MotionState& kf, TwistPrior* prior) const override {
    if (!kf.has_inertial || !has_imu_) return false;
    const int64_t t_imu = kf.t_ns + sToNs(time_offset_s_);
    if (!buffer_.covers(t_imu, t_imu)) return false;
    const Vec3 gyro = buffer_.interpolate(t_imu).gyro_rad_s;
    const RxSO3d T_wm_wf = metricFromFree(kf);
    if (prior) {
      prior->mean = imuTwistPrior(gyro, kf.v_wm, kf.bias_gyro, kf.T_c_w, T_wm_wf, T_cm_i_);  // eq. 32
      const double info_t = std::pow(kf.scale / o_.twist_sigma_trans_m_s, 2);
      const double info_r = std::pow(1.0 / o_.twist_sigma_rot_rad_s, 2);
      prior->information.setZero();
      prior->information.diagonal() << Vec3::Constant(info_t), Vec3::Constant(info_r);
    }
    return true;
  }

  // The metric state the IMU predicts at t (pose, velocity, biases), or false without an inertial
  // state or IMU coverage. predict() maps its pose to T_Cf_Wf.
  bool predictState(const MotionState& last, int64_t t_ns, ImuState* out) const {
    if (!last.has_inertial || !has_imu_ || t_ns < last.t_ns) return false;
    const int64_t off = sToNs(time_offset_s_);
    if (!buffer_.covers(last.t_ns + off, t_ns + off)) return false;
    ImuState s;
    setPose(&s, imuPoseFromCamera(last.T_c_w, metricFromFree(last), T_cm_i_));
    s.v_w = last.v_wm;
    s.bias.gyro = last.bias_gyro;
    s.bias.accel = last.bias_accel;
    if (t_ns == last.t_ns) {
      *out = s;
      return true;
    }
    const ImuPreintegration pre =
        ImuPreintegration::fromBuffer(buffer_, last.t_ns, t_ns, noise_, s.bias, time_offset_s_);
    *out = rsvio::predictState(s, pre);
    return true;
  }

  // The same Sigma for the twist energy inside the window optimisation (visual-inertial runs).
  bool twistEnergySigma(double* sigma_trans_m_s, double* sigma_rot_rad_s) const override {
    *sigma_trans_m_s = o_.twist_sigma_trans_m_s;
    *sigma_rot_rad_s = o_.twist_sigma_rot_rad_s;
    return true;
  }

  bool smoothMotionInformation(Mat6* information) const override {
    if (!(o_.smooth_twist_info_trans > 0.0 || o_.smooth_twist_info_rot > 0.0)) return false;
    if (information) {
      information->setZero();
      information->diagonal() << Vec3::Constant(o_.smooth_twist_info_trans), Vec3::Constant(o_.smooth_twist_info_rot);
    }
    return true;
  }

  const ImuMotionOptions& options() const { return o_; }

 private:
  static RxSO3d metricFromFree(const MotionState& s) { return RxSO3d(s.scale, s.T_wm_wf.so3()); }

  bool imuGuess(const MotionState& last, int64_t t_ns, SE3d* guess) const {
    ImuState s;
    if (!predictState(last, t_ns, &s)) return false;
    *guess = cameraPoseFromImu(SE3d(s.R_w_i, s.p_w_i), metricFromFree(last), T_cm_i_);
    return true;
  }

  // Before the initialisation: cv's camera centre, the rotation integrated by the gyroscope from the
  // last frame with a zero bias (contract above).
  bool gyroGuess(const MotionState& last, const SE3d& cv, int64_t t_ns, SE3d* guess) const {
    if (!has_imu_ || t_ns <= last.t_ns) return false;
    const int64_t off = sToNs(time_offset_s_);
    if (!buffer_.covers(last.t_ns + off, t_ns + off)) return false;
    const SO3d dR = ImuPreintegration::fromBuffer(buffer_, last.t_ns, t_ns, noise_, ImuBias{}, time_offset_s_).deltaR();
    const SO3d R_ci = T_cm_i_.so3();
    const SO3d R_w_c = last.T_c_w.so3().inverse() * R_ci * dR * R_ci.inverse();
    *guess = SE3d(R_w_c, cv.inverse().translation()).inverse();
    return true;
  }

  // exp(v (t - t_last)) T_last with v the per-second velocity between the last two frames.
  static SE3d constantVelocityGuess(const std::vector<MotionState>& h, int64_t t_ns) {
    const MotionState& last = h.back();
    if (h.size() < 2) return last.T_c_w;
    const MotionState& prev = h[h.size() - 2];
    const double dt = nsToS(last.t_ns - prev.t_ns);
    if (!(dt > 1e-12)) return last.T_c_w;
    const Vec6 v = (last.T_c_w * prev.T_c_w.inverse()).log() / dt;
    return SE3d::exp(v * nsToS(t_ns - last.t_ns)) * last.T_c_w;
  }

  ImuMotionOptions o_;
  ImuBuffer buffer_;
  bool has_imu_ = false;
  ImuNoise noise_;
  SE3d T_cm_i_;
  double time_offset_s_ = 0.0;
};

}  // namespace rsvio
