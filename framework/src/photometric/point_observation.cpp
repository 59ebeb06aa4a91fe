#include "rsvio/photometric/point_observation.h"

#include "rsvio/lie/se3.h"

namespace rsvio {

std::vector<HostPoint> makeHostPoints(const CameraModel& camera, const ImageLevel& host_level0,
                                      const std::vector<Vec2>& uv, const std::vector<double>& idepth,
                                      const ResidualOptions& options, std::vector<int>* kept) {
  Eigen::Matrix2Xd q(2, static_cast<Eigen::Index>(uv.size()));
  for (size_t i = 0; i < uv.size(); ++i) q.col(static_cast<Eigen::Index>(i)) = uv[i];
  Eigen::Matrix3Xd b;
  std::vector<uint8_t> valid;
  std::vector<Jac32> J;
  camera.unproject(q, b, valid, &J);
  std::vector<HostPoint> out;
  out.reserve(uv.size());
  if (kept) kept->clear();
  for (size_t i = 0; i < uv.size(); ++i) {
    if (!valid[i]) continue;
    HostPoint p;
    p.uv = uv[i];
    p.bearing = b.col(static_cast<Eigen::Index>(i));
    p.d_bearing_d_uv = J[i];
    p.idepth = i < idepth.size() ? idepth[i] : 0.0;
    if (!makePatternHost(host_level0, static_cast<float>(uv[i].x()), static_cast<float>(uv[i].y()), options,
                         &p.pattern))
      continue;
    out.push_back(p);
    if (kept) kept->push_back(static_cast<int>(i));
  }
  return out;
}

namespace detail {

namespace {

Eigen::Matrix<double, 3, 6> dLeft(const Vec3& p) {
  Eigen::Matrix<double, 3, 6> J;
  J.leftCols<3>().setIdentity();
  J.rightCols<3>() = -SO3d::hat(p);
  return J;
}

// Global shutter: every row at t = 0, so the RS solve reduces to one projection and the twists and
// the line delay have no effect; the same Jacobians as rs_projection.h without a per-point exp.
void projectGlobal(const CameraModel& camera, const ObservationFrames& frames, const std::vector<HostPoint>& points,
                   std::vector<Observation>& out) {
  const SE3d T_th = frames.target.T_c_w0 * frames.host.T_c_w0.inverse();
  const Eigen::Matrix3d R_th = T_th.rotationMatrix();
  const Eigen::Matrix3d R_t = frames.target.T_c_w0.rotationMatrix();
  const Eigen::Index n = static_cast<Eigen::Index>(points.size());
  Eigen::Matrix3Xd X_t(3, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const HostPoint& p = points[static_cast<size_t>(i)];
    X_t.col(i) = p.idepth > 0.0 ? Vec3(T_th * Vec3(p.bearing / p.idepth)) : Vec3::Constant(std::nan(""));
  }
  Eigen::Matrix2Xd uv;
  std::vector<uint8_t> valid;
  std::vector<Jac23> Jc;
  camera.project(X_t, uv, valid, &Jc);
  for (Eigen::Index i = 0; i < n; ++i) {
    const HostPoint& p = points[static_cast<size_t>(i)];
    RsHostProjection& r = out[static_cast<size_t>(i)].proj;
    r = RsHostProjection();
    r.uv = uv.col(i);
    r.iterations = 1;
    r.converged = true;
    r.valid = valid[static_cast<size_t>(i)] && p.idepth > 0.0;
    if (!r.valid) continue;
    const Jac23& J = Jc[static_cast<size_t>(i)];
    const Vec3 X_h = p.bearing / p.idepth;
    r.d_uv_d_T0 = J * dLeft(X_t.col(i));
    r.d_uv_d_X = J * R_t;
    const Eigen::Matrix<double, 2, 3> JR = J * R_th;
    r.d_uv_d_Th0 = -JR * dLeft(X_h);
    r.d_uv_d_idepth = JR * (-p.bearing / (p.idepth * p.idepth));
  }
}

}  // namespace

void projectObservations(const CameraModel& camera, const RowTiming& timing, const ObservationFrames& frames,
                         const std::vector<HostPoint>& points, std::vector<Observation>& out) {
  const Eigen::Index n = static_cast<Eigen::Index>(points.size());
  out.resize(points.size());
  if (timing.dtDv() == 0.0 && timing.direction == 0.0) {
    projectGlobal(camera, frames, points, out);
    const double alpha = frames.exposure_ratio * std::exp(frames.target_affine.a - frames.host_affine.a);
    const Eigen::Matrix3d R_w_h = frames.host.T_c_w0.rotationMatrix().transpose();
    for (size_t i = 0; i < points.size(); ++i) {
      Observation& o = out[i];
      o.alpha = alpha;
      if (o.proj.valid) o.warp = o.proj.d_uv_d_X * R_w_h * points[i].d_bearing_d_uv / points[i].idepth;
    }
    return;
  }
  Eigen::Matrix3Xd bearing(3, n);
  Eigen::VectorXd v_h(n), rho(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const HostPoint& p = points[static_cast<size_t>(i)];
    bearing.col(i) = p.bearing;
    v_h[i] = p.uv.y();
    rho[i] = p.idepth;
  }
  std::vector<RsHostProjection> proj;
  projectRollingShutter(camera, timing, frames.host, frames.target, bearing, v_h, rho, proj);
  out.resize(points.size());
  const double alpha = frames.exposure_ratio * std::exp(frames.target_affine.a - frames.host_affine.a);
  const Eigen::Matrix3d R_w_h0 = frames.host.T_c_w0.rotationMatrix().transpose();
  for (size_t i = 0; i < points.size(); ++i) {
    Observation& o = out[i];
    o.proj = proj[i];
    o.alpha = alpha;
    if (!o.proj.valid) continue;
    // W = d p' / d uv_h at fixed rho: X_w = R_w_h(t_h) b(uv_h) / rho + const.
    const HostPoint& p = points[i];
    const double t_h = timing.rowTime(p.uv.y());
    const Eigen::Matrix3d R_w_h = R_w_h0 * SE3d::exp(-frames.host.xi * t_h).rotationMatrix();
    o.warp = o.proj.d_uv_d_X * R_w_h * p.d_bearing_d_uv / p.idepth;
  }
}

}  // namespace detail

ObservationJacobians observationJacobians(const Observation& obs, const HostPoint& point,
                                          const ObservationFrames& frames) {
  Eigen::Matrix<double, kPatternSize, 2> G;
  for (int k = 0; k < kPatternSize; ++k) G.row(k) << obs.res.gx[k], obs.res.gy[k];
  ObservationJacobians J;
  J.d_r_d_T_target = G * obs.proj.d_uv_d_T0;
  J.d_r_d_xi_target = G * obs.proj.d_uv_d_xi;
  J.d_r_d_T_host = G * obs.proj.d_uv_d_Th0;
  J.d_r_d_xi_host = G * obs.proj.d_uv_d_xi_h;
  J.d_r_d_idepth = G * obs.proj.d_uv_d_idepth;
  J.d_r_d_line_delay = G * obs.proj.d_uv_d_line_delay;
  affineJacobians(point.pattern, frames.host_affine, obs.alpha, &J.d_r_d_ab_host, &J.d_r_d_ab_target);
  return J;
}

}  // namespace rsvio
