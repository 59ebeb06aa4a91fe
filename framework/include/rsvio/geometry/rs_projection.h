// Rolling-shutter projection (paper sec. IV-A, eqs. 6-7): where a 3D point appears in a target frame
// whose pose moves during the readout, and the Jacobians of that pixel w.r.t. the state.
//
// Contract
// - Target frame: central pose T_c_w^0 (world -> camera, at the image timestamp, i.e. raw row y0) and
//   twist xi = (translation; rotation) per second, left: T_c_w(t) = exp(xi t) T_c_w^0 (eq. 6); with a
//   known angular acceleration w_dot (RsFrame, zero by default) the rows also turn by exp(w_dot t^2 / 2).
// - Raw row v is read at t(v) = dt_dv (v - y0), dt_dv = direction * line_delay_s (RowTiming;
//   conventions.md "Time"). Rows are raw (distorted) rows: the camera projects through its distortion,
//   so the row IS f_d of eq. 7 and no undistorted image is needed.
// - The projection solves the rolling-shutter constraint  v = project(T_c_w(t(v)) X_w).v  for v by
//   Newton's method on the row (at most max_iterations evaluations; converged flag; never loops).
//   A global shutter (dt_dv = 0) takes the same code path and stops after one evaluation.
// - Jacobians are total derivatives of uv at the solution, including the implicit dependence of the
//   row on the state (implicit function theorem, derivation in docs/rs_projection.md):
//     d uv / d s = M * (d project / d s at fixed row),   M = (I - a e_v^T)^-1,
//     a = d project / d v at fixed state = J_cam * (d p / d t) * dt_dv,  e_v = (0, 1)^T.
//   Poses use the optimiser's LEFT perturbation T <- exp(delta) T (rsvio/lie/lie.h); twists are
//   perturbed additively (xi <- xi + d); the line delay additively in seconds.
// - Validity: the camera says valid (in front, inside its domain), the iteration converged, and
//   1 - a_y is not near 0 (a point moving down the image as fast as the readout has no unique row).
//   Whether the pixel lies inside the image is the caller's test (CameraModel::inImage).
// - Host-frame points (DSO's parametrisation): bearing b in host camera h, observed at host raw row v_h,
//   inverse depth rho > 0: X_w = T_h_w(t_h)^-1 (b / rho), T_h_w(t) = exp(xi_h t) T_h_w^0, t_h = t(v_h).
//   Host and target are frames of the same camera (one RowTiming); d uv / d line_delay includes the
//   host's row time.
// - Batch calls: one call per host-target pair; each Newton iteration is one camera batch call.
#pragma once
#include <Eigen/Core>
#include <cmath>
#include <vector>

#include "rsvio/core/types.h"
#include "rsvio/lie/se3.h"

namespace rsvio {

class CameraModel;
class ShutterModel;

using Mat26 = Eigen::Matrix<double, 2, 6>;

// exp(xi t) of one twist at many row times t (eq. 6 along a frame's rows), as a rotation matrix and a
// translation. With W = [omega]x, phi = |omega| t and SO(3)'s coefficients of lie_common.h
// (a = sin(phi)/phi, b = (1 - cos phi)/phi^2, c = (phi - sin phi)/phi^3, series below 1 rad):
//   R(t) = I + t a W + t^2 b W^2,   p(t) = Jl(omega t) v t = t v + t^2 b (W v) + t^3 c (W W v),
// the same as SE3d::exp(xi * t) (rsvio/lie/se3.h), with W, W^2, W v and W W v formed once per twist.
struct TwistExp {
  Mat3 W = Mat3::Zero(), W2 = Mat3::Zero();
  Vec3 v = Vec3::Zero(), Wv = Vec3::Zero(), WWv = Vec3::Zero();
  // For SE3's Q(xi t) (rsvio/lie/se3.h calcQ with U = t [v]x, W = t [w]x), U = [v]x:
  // S1 = WU + UW, S2 = WUW, S3 = WWU + UWW - 3 WUW, S4 = WUWW + WWUW.
  Mat3 U = Mat3::Zero(), S1 = Mat3::Zero(), S2 = Mat3::Zero(), S3 = Mat3::Zero(), S4 = Mat3::Zero();
  double theta = 0.0;
  bool zero = true;
  explicit TwistExp(const Vec6& xi) {
    v = xi.head<3>();
    const Vec3 w = xi.tail<3>();
    zero = xi.isZero(0.0);
    theta = w.norm();
    W = SO3d::hat(w);
    W2 = w * w.transpose() - (theta * theta) * Mat3::Identity();
    Wv = w.cross(v);
    WWv = w.cross(Wv);
    U = SO3d::hat(v);
    const Mat3 WU = W * U, UW = U * W;
    S1 = WU + UW;
    S2 = WU * W;
    S3 = W * WU + UW * W - 3.0 * S2;
    S4 = S2 * W + W * S2;
  }
  // [I, -[p]x] Jl(xi t) = [J, Q - [p]x J] for SE3's left Jacobian Jl = [J, Q; 0, J] at the row time t
  // (the rolling-shutter Jacobian's factor, rs_projection.cpp), from the products above:
  //   J = I + t b W + t^2 c W^2,  Q = t/2 U + c t^2 S1 + c t^3 S2 + q2 t^3 S3 + q3 t^4 S4,
  // b, c, q2, q3 the coefficients of rsvio/lie at |w t|. The same as SE3d::leftJacobian(xi t) up to
  // rounding (tests/framework/geometry); zero twist or t = 0: [I, -[p]x] exactly.
  Eigen::Matrix<double, 3, 6> dLeftActionTimesJl(double t, const Vec3& p) const {
    Eigen::Matrix<double, 3, 6> M;
    const Mat3 P = SO3d::hat(p);
    if (zero || t == 0.0) {
      M.leftCols<3>().setIdentity();
      M.rightCols<3>() = -P;
      return M;
    }
    const double phi = std::abs(theta * t);
    const double c = lie::thetaMinusSinOverTheta3(phi), t2 = t * t, t3 = t2 * t;
    const Mat3 J = Mat3::Identity() + (t * lie::oneMinusCosOverTheta2(phi)) * W + (t2 * c) * W2;
    const Mat3 Q = (0.5 * t) * U + (c * t2) * S1 + (c * t3) * S2 + (lie::se3QCoeff2(phi) * t3) * S3 +
                   (lie::se3QCoeff3(phi) * t2 * t2) * S4;
    M.leftCols<3>() = J;
    M.rightCols<3>() = Q - P * J;
    return M;
  }
  // The global-shutter case (zero twist or t = 0) is exactly the identity.
  void at(double t, Mat3& R, Vec3& p) const {
    if (zero || t == 0.0) {
      R.setIdentity();
      p.setZero();
      return;
    }
    const double phi = std::abs(theta * t);
    const double b = t * t * lie::oneMinusCosOverTheta2(phi);
    R = rotationAt(t, phi, b);
    p = t * v + b * Wv + (t * t * t * lie::thetaMinusSinOverTheta3(phi)) * WWv;
  }
  // The rotation alone.
  Mat3 rotation(double t) const {
    if (zero || t == 0.0) return Mat3::Identity();
    const double phi = std::abs(theta * t);
    return rotationAt(t, phi, t * t * lie::oneMinusCosOverTheta2(phi));
  }
  // exp(xi t) applied to a point.
  Vec3 apply(double t, const Vec3& X) const {
    Mat3 R;
    Vec3 p;
    at(t, R, p);
    return R * X + p;
  }

 private:
  // R(t) = I + t a W + t^2 b W^2 with b_t = t^2 b given (at() needs it for p too).
  Mat3 rotationAt(double t, double phi, double b_t) const {
    return Mat3::Identity() + (t * lie::sinOverTheta(phi)) * W + b_t * W2;
  }
};

// When each raw row is read: t(v) = direction * line_delay_s * (v - y0).
struct RowTiming {
  double y0 = 0.0;            // raw row of the image timestamp, (h - 1) / 2
  double line_delay_s = 0.0;  // s per row (>= 0 in practice; any value works for the derivatives)
  double direction = 0.0;     // +1 top_down, -1 bottom_up, 0 global shutter

  double dtDv() const { return direction * line_delay_s; }
  double rowTime(double v) const { return dtDv() * (v - y0); }
  double dRowTimeDLineDelay(double v) const { return direction * (v - y0); }

  static RowTiming global(double y0) { return RowTiming{y0, 0.0, 0.0}; }
  static RowTiming rolling(double y0, double line_delay_s, bool top_down) {
    return RowTiming{y0, line_delay_s, top_down ? 1.0 : -1.0};
  }
  // From the plugins: y0 from the camera's calibration; the direction from the sign bit of
  // rowTimeDerivative() (a zero line delay read bottom_up reports -0.0, shutter.h).
  static RowTiming from(const ShutterModel& shutter, const CameraModel& camera);
};

struct RsProjectionOptions {
  int max_iterations = 10;     // camera evaluations per point, at most
  double tolerance_px = 1e-6;  // |project(T(t(v)) X).v - v| at convergence
  double min_singular = 1e-3;  // |1 - a_y| below this: no unique row, invalid
  bool jacobians = true;
};

// One target frame: central pose and twist (eq. 6), and optionally the rate of change of the twist's
// rotation, w_dot (rad/s^2, the camera's angular acceleration with the twist's sign: w = -omega_c, so
// w_dot = -d omega_c / dt). w_dot is known (the gyroscope's, imu.readout_angular_acceleration), not
// optimised: it takes the rows' rotation to second order in the row time,
//   T_c_w(t) = exp((0; w_dot t^2 / 2)) exp(xi t) T_c_w^0,
// which is exp(xi t + (0; w_dot t^2 / 2)) T_c_w^0 up to O(t^3). Zero (the default) is eq. 6 exactly.
struct RsFrame {
  SE3d T_c_w0;
  Vec6 xi = Vec6::Zero();  // per second, (translation; rotation)
  Vec3 w_dot = Vec3::Zero();
};

// The second-order rotation of RsFrame::w_dot at row time t, A(t) = exp(w_dot t^2 / 2): a rotation about
// the fixed axis n = w_dot / |w_dot| by theta = |w_dot| t^2 / 2, so
//   A(t) = I + sin(theta) [n]x + 2 sin^2(theta / 2) [n]x^2,   d A / d t = [g(t)]x A(t),  g(t) = w_dot t
// exactly (the axis does not turn, so SO(3)'s left Jacobian acts as the identity on it). [n]x and
// [n]x^2 are formed once per frame; A(t) costs a sine, a cosine and 18 products. A zero w_dot gives the
// identity and zero.
class ReadoutRotation {
 public:
  explicit ReadoutRotation(const Vec3& w_dot) : w_dot_(w_dot), norm_(w_dot.norm()) {
    if (norm_ == 0.0) return;
    K_ = SO3d::hat(w_dot / norm_);
    K2_ = K_ * K_;
  }
  bool zero() const { return norm_ == 0.0; }
  Mat3 A(double t) const {
    if (norm_ == 0.0 || t == 0.0) return Mat3::Identity();
    const double theta = 0.5 * norm_ * t * t, s = std::sin(0.5 * theta);
    return Mat3::Identity() + std::sin(theta) * K_ + (2.0 * s * s) * K2_;
  }
  Vec3 g(double t) const { return t * w_dot_; }

 private:
  Vec3 w_dot_;
  double norm_ = 0.0;
  Mat3 K_ = Mat3::Zero(), K2_ = Mat3::Zero();
};

// The pose of a frame's row at row time t (the contract's T_c_w(t); not for hot loops).
inline SE3d rsPoseAt(const RsFrame& f, double t) {
  if (t == 0.0) return f.T_c_w0;
  const SE3d T = SE3d::exp(f.xi * t) * f.T_c_w0;
  if (f.w_dot.isZero(0.0)) return T;
  return SE3d(SO3d::exp((0.5 * t * t) * f.w_dot), Vec3::Zero()) * T;
}

// A world point projected into the target.
struct RsProjection {
  Vec2 uv = Vec2::Zero();
  double t_s = 0.0;         // row time of the solution, relative to the target's timestamp
  bool valid = false;
  bool converged = false;
  int iterations = 0;       // camera evaluations used
  Mat26 d_uv_d_T0 = Mat26::Zero();   // left perturbation of T_c_w^0
  Mat26 d_uv_d_xi = Mat26::Zero();   // target twist
  Eigen::Matrix<double, 2, 3> d_uv_d_X = Eigen::Matrix<double, 2, 3>::Zero();  // world point
  Vec2 d_uv_d_line_delay = Vec2::Zero();  // per second of line delay
};

// A host-frame point projected into the target: the world-point fields, plus the host's.
struct RsHostProjection : RsProjection {
  Mat26 d_uv_d_Th0 = Mat26::Zero();  // left perturbation of the host's T_h_w^0
  Mat26 d_uv_d_xi_h = Mat26::Zero(); // host twist
  Vec2 d_uv_d_idepth = Vec2::Zero(); // inverse depth rho
  // d_uv_d_line_delay here is total: target row time and host row time t_h = t(v_h).
};

// World points X_w (3xN) into the target frame. out is resized to N.
void projectRollingShutter(const CameraModel& camera, const RowTiming& timing, const RsFrame& target,
                           const Eigen::Matrix3Xd& X_w, std::vector<RsProjection>& out,
                           const RsProjectionOptions& options = {});

// Host points (unit bearings 3xN at host raw rows v_h, inverse depths rho) into the target frame.
void projectRollingShutter(const CameraModel& camera, const RowTiming& timing, const RsFrame& host,
                           const RsFrame& target, const Eigen::Matrix3Xd& bearing_h,
                           const Eigen::VectorXd& v_h, const Eigen::VectorXd& idepth,
                           std::vector<RsHostProjection>& out, const RsProjectionOptions& options = {});

// The part of a host point's projection that does not depend on the target: the rotation E that takes
// the bearing into the host's central frame at its row time t_h = t(v_h), exp(-xi_h t_h) A_h(t_h)^T with
// A_h the host's ReadoutRotation (identity without w_dot), the point Z = T_h_w(t_h)-to-central of
// (b / rho) = exp(-xi_h t_h) A_h^T (b / rho) + p, dZ = [I, -[Z]x] Jl(-xi_h t_h) (d Z / d xi_h before its
// factor -t_h; zero for t_h = 0 or without Jacobians), and dZ_dt_acc, the w_dot part of d Z / d t_h
// (-E (g x b / rho); zero without w_dot). rsHostPoint() is the one place these are computed, so a projection
// from cached host points (the bundle adjustment computes them once per point and linearisation and
// reuses them for every target) is bit-identical to the one that computes them.
struct RsHostPoint {
  Mat3 E = Mat3::Identity();
  Vec3 Z = Vec3::Zero();
  Eigen::Matrix<double, 3, 6> dZ = Eigen::Matrix<double, 3, 6>::Zero();
  Vec3 dZ_dt_acc = Vec3::Zero();
};
// ex_h = TwistExp(the host twist xi_h); rho > 0 and finite (the caller skips the others); w_dot_h the
// host's RsFrame::w_dot.
RsHostPoint rsHostPoint(const TwistExp& ex_h, double t_h, const Vec3& bearing_h, double rho,
                        bool jacobians, const Vec3& w_dot_h = Vec3::Zero());
// As above, with the host points given (host_points[i] = rsHostPoint(...) of column i for every column
// with a valid inverse depth; the others are not read).
void projectRollingShutter(const CameraModel& camera, const RowTiming& timing, const RsFrame& host,
                           const RsFrame& target, const Eigen::Matrix3Xd& bearing_h,
                           const Eigen::VectorXd& v_h, const Eigen::VectorXd& idepth,
                           const std::vector<RsHostPoint>& host_points, std::vector<RsHostProjection>& out,
                           const RsProjectionOptions& options = {});

// Single-point versions (not for hot loops).
RsProjection projectRollingShutter(const CameraModel& camera, const RowTiming& timing, const RsFrame& target,
                                   const Vec3& X_w, const RsProjectionOptions& options = {});
RsHostProjection projectRollingShutter(const CameraModel& camera, const RowTiming& timing, const RsFrame& host,
                                       const RsFrame& target, const Vec3& bearing_h, double v_h, double idepth,
                                       const RsProjectionOptions& options = {});

}  // namespace rsvio
