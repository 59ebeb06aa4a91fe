// Rolling-shutter projection (contract in rsvio/geometry/rs_projection.h; derivation of the Jacobians
// in docs/rs_projection.md).
#include "rsvio/geometry/rs_projection.h"

#include <cmath>

#include "rsvio/interfaces/camera.h"
#include "rsvio/interfaces/shutter.h"

namespace rsvio {

RowTiming RowTiming::from(const ShutterModel& shutter, const CameraModel& camera) {
  const double y0 = camera.calibration().rowZero();
  if (!shutter.isRolling()) return global(y0);
  return rolling(y0, shutter.lineDelay(), !std::signbit(shutter.rowTimeDerivative()));  // -0.0: bottom_up
}

namespace {

using Mat36 = Eigen::Matrix<double, 3, 6>;

// [I, -[p]x]: d(exp(d) p)/d d at d = 0 for the tangent order (translation; rotation).
Mat36 dLeftAction(const Vec3& p) {
  Mat36 J;
  J.leftCols<3>().setIdentity();
  J.rightCols<3>() = -SO3d::hat(p);
  return J;
}

// Left-multiplies a 2xK Jacobian by M = (I - a e_v^T)^-1 = [1, a_x / (1 - a_y); 0, 1 / (1 - a_y)].
template <class Derived>
void applyImplicitRow(Eigen::MatrixBase<Derived>& A, const Vec2& a) {
  const double inv = 1.0 / (1.0 - a.y());
  A.row(0) += (a.x() * inv) * A.row(1);
  A.row(1) *= inv;
}

// Solves the rolling-shutter constraint for the points X_w (one column per entry of out) and fills
// the world-point fields of *out[i].
void solveWorldPoints(const CameraModel& camera, const RowTiming& timing, const RsFrame& target,
                      const Eigen::Matrix3Xd& X_w, const std::vector<RsProjection*>& out,
                      const RsProjectionOptions& opt) {
  const size_t n = out.size();
  const double c = timing.dtDv();
  const Vec3 xi_v = target.xi.head<3>();
  const Vec3 xi_w = target.xi.tail<3>();

  const TwistExp ex(target.xi);
  const ReadoutRotation ra(target.w_dot);
  const bool acc = !ra.zero();  // the rows' second-order rotation (RsFrame::w_dot)
  std::vector<Vec3> P0(n), P(n);
  std::vector<Mat3> E(n);  // rotation of exp(xi t) at the current row (times A(t) with w_dot)
  std::vector<Vec3> dPdt(n);  // d P / d t at the current row, fixed state
  std::vector<Mat3> A(acc ? n : 0);  // ReadoutRotation's A at the current row
  std::vector<Vec3> Pxi(acc ? n : 0);  // exp(xi t) P0, before A
  std::vector<Jac23> Jc(n);
  std::vector<Vec2> a(n, Vec2::Zero());
  std::vector<double> v(n, timing.y0);  // start at t = 0: the first evaluation is the global-shutter pixel
  std::vector<size_t> active(n);
  for (size_t i = 0; i < n; ++i) {
    P0[i] = target.T_c_w0 * Vec3(X_w.col(static_cast<Eigen::Index>(i)));
    *out[i] = RsProjection();
    active[i] = i;
  }

  Eigen::Matrix3Xd Pa;
  Eigen::Matrix2Xd uva;
  std::vector<uint8_t> va;
  std::vector<Jac23> Ja;
  const bool need_J = opt.jacobians || c != 0.0;
  for (int it = 1; it <= opt.max_iterations && !active.empty(); ++it) {
    Pa.resize(3, static_cast<Eigen::Index>(active.size()));
    for (size_t k = 0; k < active.size(); ++k) {
      const size_t i = active[k];
      Vec3 p;
      const double t = timing.rowTime(v[i]);
      ex.at(t, E[i], p);  // eq. 6 at the row's time (eq. 7)
      P[i] = E[i] * P0[i] + p;
      dPdt[i] = xi_v + xi_w.cross(P[i]);  // d/dt exp(xi t) = xi^ exp(xi t)
      if (acc) {  // P = A(t) exp(xi t) P0: d P / d t = g x P + A (xi_v + xi_w x exp(xi t) P0)
        A[i] = ra.A(t);
        Pxi[i] = P[i];
        P[i] = A[i] * Pxi[i];
        E[i] = A[i] * E[i];
        dPdt[i] = ra.g(t).cross(P[i]) + A[i] * dPdt[i];
      }
      Pa.col(static_cast<Eigen::Index>(k)) = P[i];
    }
    camera.project(Pa, uva, va, need_J ? &Ja : nullptr);  // one batch call per iteration
    std::vector<size_t> still;
    for (size_t k = 0; k < active.size(); ++k) {
      const size_t i = active[k];
      RsProjection& r = *out[i];
      r.iterations = it;
      r.uv = uva.col(static_cast<Eigen::Index>(k));
      r.t_s = timing.rowTime(v[i]);
      if (!va[k]) continue;  // behind the camera or outside its domain: stays invalid
      if (need_J) {
        Jc[i] = Ja[k];
        a[i] = Jc[i] * dPdt[i] * c;  // d project / d v at fixed state
      }
      const double res = r.uv.y() - v[i];
      if (c == 0.0 || std::abs(res) <= opt.tolerance_px) {
        r.converged = true;
        r.valid = std::abs(1.0 - a[i].y()) >= opt.min_singular;
        continue;
      }
      const double denom = 1.0 - a[i].y();
      if (std::abs(denom) < opt.min_singular || !std::isfinite(res)) continue;
      v[i] += res / denom;  // Newton on f(v) = project(v).v - v, f'(v) = a_y - 1
      still.push_back(i);
    }
    active.swap(still);
  }

  if (!opt.jacobians) return;
  for (size_t i = 0; i < n; ++i) {
    RsProjection& r = *out[i];
    if (!r.valid) continue;
    const double t = r.t_s;
    const Eigen::Matrix<double, 2, 3> JR = Jc[i] * E[i];
    // Partial derivatives at a fixed row, then M for the row's own dependence on the state.
    r.d_uv_d_T0 = JR * dLeftAction(P0[i]);
    if (t == 0.0)
      r.d_uv_d_xi.setZero();
    else if (acc)
      r.d_uv_d_xi = (Jc[i] * A[i]) * ex.dLeftActionTimesJl(t, Pxi[i]) * t;
    else
      r.d_uv_d_xi = Jc[i] * ex.dLeftActionTimesJl(t, P[i]) * t;
    r.d_uv_d_X = JR * target.T_c_w0.rotationMatrix();
    // The row of the solution is uv.y (equal to the iterate within tolerance; for a global shutter the
    // iterate stays at y0 while the pixel's row is uv.y).
    r.d_uv_d_line_delay = Jc[i] * dPdt[i] * timing.dRowTimeDLineDelay(r.uv.y());
    applyImplicitRow(r.d_uv_d_T0, a[i]);
    applyImplicitRow(r.d_uv_d_xi, a[i]);
    applyImplicitRow(r.d_uv_d_X, a[i]);
    applyImplicitRow(r.d_uv_d_line_delay, a[i]);
  }
}

}  // namespace

void projectRollingShutter(const CameraModel& camera, const RowTiming& timing, const RsFrame& target,
                           const Eigen::Matrix3Xd& X_w, std::vector<RsProjection>& out,
                           const RsProjectionOptions& options) {
  out.resize(static_cast<size_t>(X_w.cols()));
  std::vector<RsProjection*> ptrs(out.size());
  for (size_t i = 0; i < out.size(); ++i) ptrs[i] = &out[i];
  solveWorldPoints(camera, timing, target, X_w, ptrs, options);
}

RsHostPoint rsHostPoint(const TwistExp& ex_h, double t_h, const Vec3& bearing_h, double rho,
                        bool jacobians, const Vec3& w_dot_h) {
  RsHostPoint h;
  Vec3 p;
  ex_h.at(-t_h, h.E, p);  // exp(xi_h (-t_h))
  if (!w_dot_h.isZero(0.0) && t_h != 0.0) {  // T_h_w(t_h) = A_h exp(xi_h t_h) T_h_w0: undo A_h first
    const ReadoutRotation ra(w_dot_h);
    h.E = h.E * ra.A(t_h).transpose();
    // d (A^T y) / d t = -A^T (g x y), y = b / rho
    if (jacobians) h.dZ_dt_acc = -h.E * ra.g(t_h).cross(Vec3(bearing_h / rho));
  }
  h.Z = h.E * Vec3(bearing_h / rho) + p;
  if (jacobians && t_h != 0.0) h.dZ = ex_h.dLeftActionTimesJl(-t_h, h.Z);
  return h;
}

namespace {

// host_points: given (one per column), or null: computed here.
void projectHostPoints(const CameraModel& camera, const RowTiming& timing, const RsFrame& host,
                       const RsFrame& target, const Eigen::Matrix3Xd& bearing_h, const Eigen::VectorXd& v_h,
                       const Eigen::VectorXd& idepth, const std::vector<RsHostPoint>* host_points,
                       std::vector<RsHostProjection>& out, const RsProjectionOptions& options) {
  const Eigen::Index n = bearing_h.cols();
  // Every entry is reset below: the world-point fields by solveWorldPoints(), the host fields here
  // (one zero-fill per entry instead of two).
  out.resize(static_cast<size_t>(n));
  const SE3d T_w_h0 = host.T_c_w0.inverse();
  const Eigen::Matrix3d R_w_h0 = T_w_h0.rotationMatrix();
  const Vec3 xh_v = host.xi.head<3>(), xh_w = host.xi.tail<3>();

  // X_w = T_h_w0^-1 exp(-xi_h t_h) (b / rho); points with rho <= 0 are left out (invalid).
  std::vector<Eigen::Index> idx;
  const TwistExp ex_h(host.xi);
  std::vector<RsHostPoint> computed;
  if (!host_points) computed.resize(static_cast<size_t>(n));
  const std::vector<RsHostPoint>& hp = host_points ? *host_points : computed;
  Eigen::Matrix3Xd X(3, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double rho = idepth[i];
    if (!(rho > 0.0) || !std::isfinite(rho)) {
      out[static_cast<size_t>(i)] = RsHostProjection();
      continue;
    }
    const size_t s = static_cast<size_t>(i);
    RsHostProjection& o = out[s];
    o.d_uv_d_Th0.setZero();
    o.d_uv_d_xi_h.setZero();
    o.d_uv_d_idepth.setZero();
    if (!host_points)
      computed[s] = rsHostPoint(ex_h, timing.rowTime(v_h[i]), bearing_h.col(i), rho, options.jacobians,
                                host.w_dot);
    X.col(static_cast<Eigen::Index>(idx.size())) = T_w_h0 * hp[s].Z;
    idx.push_back(i);
  }
  X.conservativeResize(3, static_cast<Eigen::Index>(idx.size()));
  std::vector<RsProjection*> ptrs;
  for (Eigen::Index i : idx) ptrs.push_back(&out[static_cast<size_t>(i)]);
  solveWorldPoints(camera, timing, target, X, ptrs, options);

  if (!options.jacobians) return;
  for (Eigen::Index i : idx) {
    const size_t s = static_cast<size_t>(i);
    RsHostProjection& r = out[s];
    if (!r.valid) continue;
    const double rho = idepth[i];
    const double t_h = timing.rowTime(v_h[i]);
    const RsHostPoint& h = hp[s];
    const Eigen::Matrix<double, 2, 3> d_uv_d_Z = r.d_uv_d_X * R_w_h0;
    // Host pose T_h_w0 <- exp(d) T_h_w0:  X = T_h_w0^-1 exp(-d) Z.
    r.d_uv_d_Th0 = -d_uv_d_Z * dLeftAction(h.Z);
    // Host twist: Z = exp(-xi_h t_h) Y,  d Z / d xi_h = [I, -[Z]x] Jl(-xi_h t_h) (-t_h).
    if (t_h != 0.0)
      r.d_uv_d_xi_h = d_uv_d_Z * h.dZ * (-t_h);
    else
      r.d_uv_d_xi_h.setZero();
    r.d_uv_d_idepth = d_uv_d_Z * (h.E * Vec3(-bearing_h.col(i) / (rho * rho)));
    // Host row time: d Z / d t_h = -(xi_v + xi_w x Z) (+ the w_dot part).
    r.d_uv_d_line_delay +=
        d_uv_d_Z * Vec3(h.dZ_dt_acc - (xh_v + xh_w.cross(h.Z))) * timing.dRowTimeDLineDelay(v_h[i]);
  }
}

}  // namespace

void projectRollingShutter(const CameraModel& camera, const RowTiming& timing, const RsFrame& host,
                           const RsFrame& target, const Eigen::Matrix3Xd& bearing_h, const Eigen::VectorXd& v_h,
                           const Eigen::VectorXd& idepth, std::vector<RsHostProjection>& out,
                           const RsProjectionOptions& options) {
  projectHostPoints(camera, timing, host, target, bearing_h, v_h, idepth, nullptr, out, options);
}

void projectRollingShutter(const CameraModel& camera, const RowTiming& timing, const RsFrame& host,
                           const RsFrame& target, const Eigen::Matrix3Xd& bearing_h, const Eigen::VectorXd& v_h,
                           const Eigen::VectorXd& idepth, const std::vector<RsHostPoint>& host_points,
                           std::vector<RsHostProjection>& out, const RsProjectionOptions& options) {
  projectHostPoints(camera, timing, host, target, bearing_h, v_h, idepth, &host_points, out, options);
}

RsProjection projectRollingShutter(const CameraModel& camera, const RowTiming& timing, const RsFrame& target,
                                   const Vec3& X_w, const RsProjectionOptions& options) {
  std::vector<RsProjection> out;
  projectRollingShutter(camera, timing, target, Eigen::Matrix3Xd(X_w), out, options);
  return out[0];
}

RsHostProjection projectRollingShutter(const CameraModel& camera, const RowTiming& timing, const RsFrame& host,
                                       const RsFrame& target, const Vec3& bearing_h, double v_h, double idepth,
                                       const RsProjectionOptions& options) {
  std::vector<RsHostProjection> out;
  projectRollingShutter(camera, timing, host, target, Eigen::Matrix3Xd(bearing_h), Eigen::VectorXd::Constant(1, v_h),
                        Eigen::VectorXd::Constant(1, idepth), out, options);
  return out[0];
}

}  // namespace rsvio
