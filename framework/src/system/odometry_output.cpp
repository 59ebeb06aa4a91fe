// Results of the estimator (contract in rsvio/system/odometry.h; conventions.md "Outputs"): refined
// frame poses, keyframe poses, the point cloud, per-keyframe states, diagnostics rows, and finish().
#include <algorithm>
#include <cmath>
#include <sstream>

#include "odometry_impl.h"
#include "rsvio/core/time.h"

namespace rsvio {
namespace {

io::StampedPose stamped(int64_t t_ns, const SE3d& T_c_w) {
  const SE3d T_w_c = T_c_w.inverse();
  io::StampedPose p;
  p.t_ns = t_ns;
  p.p_W_X = T_w_c.translation();
  p.q_W_X = T_w_c.unit_quaternion();
  return p;
}

}  // namespace

void Odometry::Impl::recordKeyframe(const Keyframe& kf) {
  KeyframeRecord& r = keyframes[kf.kf_id];
  r.kf_id = kf.kf_id;
  r.frame_index = kf.frame_index;
  r.t_ns = kf.t_ns;
  r.state = kf.state;
  if (!rolling && kf.has_observed_twist) r.state.twist = kf.observed_twist;
}

// Twist of a keyframe seen from the poses of its neighbouring frames (per second), for global-shutter
// runs where the state has none: the central difference of the previous and next tracked frames.
Vec6 Odometry::Impl::observedTwist(Keyframe& kf) const {
  if (kf.has_observed_twist) return kf.observed_twist;
  const FrameRecord* prev = nullptr;
  const FrameRecord* next = nullptr;
  const FrameRecord* self = nullptr;
  for (const FrameRecord& f : frames) {
    if (!f.tracked) continue;
    if (f.index < kf.frame_index) prev = &f;
    if (f.index == kf.frame_index) self = &f;
    if (f.index > kf.frame_index) {
      next = &f;
      break;
    }
  }
  const FrameRecord* a = prev ? prev : self;
  const FrameRecord* b = next ? next : self;
  if (!a || !b || a == b) return Vec6::Zero();
  const double dt = nsToS(b->t_ns - a->t_ns);
  if (!(dt > 0)) return Vec6::Zero();
  const Vec6 xi = (b->T_c_w * a->T_c_w.inverse()).log() / dt;
  if (next && prev) {
    kf.observed_twist = xi;
    kf.has_observed_twist = true;
  }
  return xi;
}

void Odometry::Impl::logObservation(const ActivePoint& p, const ActiveObservation& o) {
  if (!(o.state == ObsState::kIn)) return;
  const Keyframe& host = *p.host;
  Keyframe& target = *o.target;
  ObservationRow r;
  r.t_ns = target.t_ns;
  r.frame = static_cast<int32_t>(target.frame_index);
  r.host = static_cast<int32_t>(host.frame_index);
  r.u = o.u;
  r.v = o.v;
  r.row = static_cast<float>(o.v - timing.y0);
  const CameraCalibration& c = camera->calibration();
  const double half_diag = 0.5 * std::hypot(c.width, c.height);
  r.radius = static_cast<float>(std::hypot(o.u - c.intrinsics[2], o.v - c.intrinsics[3]) / half_diag);
  r.intensity = p.pattern.color[kPatternCentre];
  r.grad_u = o.grad_u;
  r.grad_v = o.grad_v;
  // Pixel velocity d uv / dt = J_cam (xi_v + xi_w x P), P the point in the target camera.
  const Vec6 xi = rolling ? target.state.twist : observedTwist(target);
  Vec3 Z = p.bearing / p.idepth;
  if (rolling) Z = SE3d::exp(-host.state.twist * timing.rowTime(p.v)) * Z;
  const Vec3 X = host.state.T_c_w.inverse() * Z;
  const double t = timing.rowTime(o.v);
  const Vec3 P = SE3d::exp(xi * t) * (target.state.T_c_w * X);
  Vec2 uv;
  Jac23 J;
  if (camera->project(P, uv, &J)) {
    const Vec2 vel = J * (xi.head<3>() + xi.tail<3>().cross(P));
    r.vel_u = static_cast<float>(vel.x());
    r.vel_v = static_cast<float>(vel.y());
  }
  r.residual = o.mean_residual;
  r.weight = o.mean_weight;
  const double exp_ratio =
      (host.exposure_ms > 0 && target.exposure_ms > 0) ? target.exposure_ms / host.exposure_ms : 1.0;
  r.exposure_ratio =
      static_cast<float>(estimate_affine ? exp_ratio * std::exp(target.state.affine.a - host.state.affine.a) : 1.0);
  diag.observations.push_back(r);
}

void Odometry::Impl::recordPoint(const ActivePoint& p) {
  const Keyframe& host = *p.host;
  Vec3 Z = p.bearing / p.idepth;
  if (rolling) Z = SE3d::exp(-host.state.twist * timing.rowTime(p.v)) * Z;
  const Vec3 X = host.state.T_c_w.inverse() * Z;
  if (!X.allFinite()) return;
  map_points.push_back(MapPoint{X.cast<float>(), p.pattern.color[kPatternCentre]});
}

void Odometry::finish() {
  Impl& m = *impl_;
  if (!m.initialized && !m.failed) {
    // The sequence ended before the monocular start succeeded: nothing was estimated, and saying
    // "ok" would hide it.
    std::ostringstream os;
    os << "monocular initialisation did not succeed in the " << m.frames.size()
       << " frames of the sequence: " << m.initializer->status();
    m.fail(os.str());
  }
  if (m.window.empty()) return;
  if (!m.failed && m.window.size() >= 2) {
    ScopedStage st(m.stages, "optimise");
    m.last_ba = m.ba->optimize(m.window, *m.prior, m.bo.max_iterations);
  }
  m.ba->evaluate(m.window, *m.prior);
  for (auto& kf : m.window) {
    m.observedTwist(*kf);
    m.recordKeyframe(*kf);
  }
  for (auto& kf : m.window) {
    for (const ActivePoint& p : kf->points) {
      for (const ActiveObservation& o : p.obs) m.logObservation(p, o);
      if (p.numIn() > 0) m.recordPoint(p);
    }
    kf->points.clear();
    kf->candidates.clear();
  }
}

io::Trajectory Odometry::frameTrajectory() const {
  const Impl& m = *impl_;
  io::Trajectory t;
  t.frame = io::PoseFrame::kCamera;
  for (const FrameRecord& f : m.frames) {
    if (!f.tracked) continue;
    SE3d T = f.T_c_w;
    const auto it = m.keyframes.find(f.ref_kf_id);
    if (it != m.keyframes.end()) T = f.T_f_ref * it->second.state.T_c_w;
    // A keyframe still in the window: its current state.
    for (const auto& kf : m.window)
      if (kf->kf_id == f.ref_kf_id) T = f.T_f_ref * kf->state.T_c_w;
    t.poses.push_back(stamped(f.t_ns, T));
  }
  std::stable_sort(t.poses.begin(), t.poses.end(),
                   [](const io::StampedPose& a, const io::StampedPose& b) { return a.t_ns < b.t_ns; });
  return t;
}

io::Trajectory Odometry::keyframeTrajectory() const {
  const Impl& m = *impl_;
  io::Trajectory t;
  t.frame = io::PoseFrame::kCamera;
  std::map<int64_t, SE3d> by_time;
  for (const auto& [id, r] : m.keyframes) by_time[r.t_ns] = r.state.T_c_w;
  for (const auto& kf : m.window) by_time[kf->t_ns] = kf->state.T_c_w;
  for (const auto& [ts, T] : by_time) t.poses.push_back(stamped(ts, T));
  return t;
}

std::vector<MapPoint> Odometry::points() const {
  const Impl& m = *impl_;
  std::vector<MapPoint> out = m.map_points;
  for (const auto& kf : m.window)
    for (const ActivePoint& p : kf->points) {
      Vec3 Z = p.bearing / p.idepth;
      if (m.rolling) Z = SE3d::exp(-kf->state.twist * m.timing.rowTime(p.v)) * Z;
      const Vec3 X = kf->state.T_c_w.inverse() * Z;
      if (X.allFinite()) out.push_back(MapPoint{X.cast<float>(), p.pattern.color[kPatternCentre]});
    }
  return out;
}

std::vector<StateRow> Odometry::states() const {
  const Impl& m = *impl_;
  std::map<int64_t, StateRow> rows;
  for (const auto& [id, r] : m.keyframes) {
    StateRow s;
    s.t_ns = r.t_ns;
    s.twist = r.state.twist;
    rows[r.t_ns] = s;
  }
  for (const auto& kf : m.window) {
    StateRow s;
    s.t_ns = kf->t_ns;
    s.twist = m.rolling ? kf->state.twist : (kf->has_observed_twist ? kf->observed_twist : Vec6::Zero());
    rows[kf->t_ns] = s;
  }
  std::vector<StateRow> out;
  for (const auto& [t, s] : rows) out.push_back(s);
  return out;
}

}  // namespace rsvio
