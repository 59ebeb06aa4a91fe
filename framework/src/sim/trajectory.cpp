// Evaluation of the analytic trajectory (rsvio/sim/trajectory.h): poses, velocities, accelerations,
// body rates and their statistics. The fit that chooses amplitudes is in trajectory_fit.cpp.
#include <cmath>

#include "rsvio/sim/trajectory.h"

namespace rsvio::sim {

namespace {

// The level camera looking along world +x: camera x -> world -y, camera y -> world -z, z -> world +x.
Mat3 levelCamera() {
  Mat3 M;
  M << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  return M;
}

Mat3 rotX(double a) {
  Mat3 R;
  const double c = std::cos(a), s = std::sin(a);
  R << 1, 0, 0, 0, c, -s, 0, s, c;
  return R;
}

Mat3 rotZ(double a) {
  Mat3 R;
  const double c = std::cos(a), s = std::sin(a);
  R << c, -s, 0, s, c, 0, 0, 0, 1;
  return R;
}

Mat3 hat(const Vec3& w) {
  Mat3 W;
  W << 0, -w.z(), w.y(), w.z(), 0, -w.x(), -w.y(), w.x(), 0;
  return W;
}

void addWaves(const std::vector<Wave>& waves, double scale, double t, double& f, double& df, double& ddf) {
  for (const Wave& w : waves) {
    const double arg = w.w * t + w.phase;
    const double s = std::sin(arg), c = std::cos(arg);
    const double a = scale * w.amp;
    f += a * s;
    df += a * w.w * c;
    ddf -= a * w.w * w.w * s;
  }
}

}  // namespace

Eigen::Isometry3d BodyState::T_W_B() const {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = q_W_B.toRotationMatrix();
  T.translation() = p_W_B;
  return T;
}

void SimTrajectory::signal(int i, double t, double& f, double& df, double& ddf) const {
  f = base_[i];
  df = ddf = 0.0;
  const bool rot = i >= 3;
  addWaves(slow_[i], scale_[rot ? 2 : 0], t, f, df, ddf);
  addWaves(fast_[i], scale_[rot ? 3 : 1], t, f, df, ddf);
}

BodyState SimTrajectory::state(double t) const {
  BodyState s;
  s.t_s = t;
  double f[kSignals], df[kSignals], ddf[kSignals];
  for (int i = 0; i < kSignals; ++i) signal(i, t, f[i], df[i], ddf[i]);
  s.p_W_B = Vec3(f[0], f[1], f[2]);
  s.v_W = Vec3(df[0], df[1], df[2]);
  s.a_W = Vec3(ddf[0], ddf[1], ddf[2]);

  // R = A M B C with A = Rz(yaw), B = Rx(pitch), C = Rz(roll). From R' = R [omega_B]x:
  //   omega_B = C^T u + roll' e3,   u = B^T M^T e3 yaw' + pitch' e1,   M^T e3 = (0, -1, 0).
  const double yaw = f[3], pitch = f[4], roll = f[5];
  const Mat3 A = rotZ(yaw), B = rotX(pitch), C = rotZ(roll);
  const Mat3 R = A * levelCamera() * B * C;
  s.q_W_B = Eigen::Quaterniond(R).normalized();
  const Vec3 m(0.0, -1.0, 0.0);
  const Vec3 e1 = Vec3::UnitX(), e3 = Vec3::UnitZ();
  const Vec3 u = B.transpose() * m * df[3] + df[4] * e1;
  s.omega_B = C.transpose() * u + df[5] * e3;
  // alpha_B = d/dt omega_B, using (B^T)' = -[pitch' e1]x B^T and (C^T)' = -[roll' e3]x C^T.
  const Vec3 du = -hat(df[4] * e1) * (B.transpose() * m) * df[3] + B.transpose() * m * ddf[3] + ddf[4] * e1;
  s.alpha_B = -hat(df[5] * e3) * (C.transpose() * u) + C.transpose() * du + ddf[5] * e3;
  return s;
}

Eigen::Isometry3d SimTrajectory::pose(double t) const { return state(t).T_W_B(); }

MotionStats SimTrajectory::stats(double rate_hz) const {
  MotionStats st;
  st.duration_s = duration_s_;
  const int n = std::max(1, static_cast<int>(std::floor(duration_s_ * rate_hz)));
  const double dt = duration_s_ / n;
  st.min_position = Vec3::Constant(1e300);
  st.max_position = Vec3::Constant(-1e300);
  constexpr double kDeg = 180.0 / M_PI;
  for (int k = 0; k < n; ++k) {
    const double t = (k + 0.5) * dt;  // midpoints: the mean of a sampled signal over [0, T]
    const BodyState s = state(t);
    const double v = s.v_W.norm(), a = s.a_W.norm();
    const double w = s.omega_B.norm() * kDeg, al = s.alpha_B.norm() * kDeg;
    st.mean_speed_m_s += v;
    st.mean_accel_m_s2 += a;
    st.mean_rot_speed_deg_s += w;
    st.mean_rot_accel_deg_s2 += al;
    st.max_speed_m_s = std::max(st.max_speed_m_s, v);
    st.max_accel_m_s2 = std::max(st.max_accel_m_s2, a);
    st.max_rot_speed_deg_s = std::max(st.max_rot_speed_deg_s, w);
    st.max_rot_accel_deg_s2 = std::max(st.max_rot_accel_deg_s2, al);
    st.min_position = st.min_position.cwiseMin(s.p_W_B);
    st.max_position = st.max_position.cwiseMax(s.p_W_B);
    double f, df, ddf;
    signal(4, t, f, df, ddf);
    st.max_abs_pitch_deg = std::max(st.max_abs_pitch_deg, std::abs(f) * kDeg);
    signal(5, t, f, df, ddf);
    st.max_abs_roll_deg = std::max(st.max_abs_roll_deg, std::abs(f) * kDeg);
  }
  st.path_length_m = st.mean_speed_m_s * dt;
  st.mean_speed_m_s /= n;
  st.mean_accel_m_s2 /= n;
  st.mean_rot_speed_deg_s /= n;
  st.mean_rot_accel_deg_s2 /= n;
  return st;
}

}  // namespace rsvio::sim
