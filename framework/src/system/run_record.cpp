// The run record (contract in run_record.h): frame and keyframe records, map points, diagnostics rows,
// and the outputs written from them (trajectories, points, states).
#include "run_record.h"

#include <algorithm>
#include <cmath>
#include <limits>

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


RunRecord::RunRecord(const CameraModel& camera, const RowTiming& timing, bool rolling, bool estimate_affine,
                     const CameraCalibration& calibration)
    : camera_(camera), timing_(timing), rolling_(rolling), estimate_affine_(estimate_affine),
      time_offset_s_(calibration.time_offset_s) {
  diag_.width = calibration.width;
  diag_.height = calibration.height;
  diag_.line_delay_s = rolling ? timing.line_delay_s : 0.0;
}

FrameRecord* RunRecord::frame(int64_t index) {
  for (auto it = frames_.rbegin(); it != frames_.rend(); ++it)
    if (it->index == index) return &*it;
  return nullptr;
}

void RunRecord::takeObservations(std::vector<ObservationRow>* rows) {
  if (provisional_) return;
  if (rows->empty()) {
    rows->swap(diag_.observations);  // the two buffers trade places: no copy, capacities kept
  } else {
    rows->insert(rows->end(), diag_.observations.begin(), diag_.observations.end());
  }
  diag_.observations.clear();
}

void RunRecord::addTrackRows(int64_t index, int64_t t_ns, int64_t from,
                             const std::vector<MonoInitializer::CornerStep>& steps) {
  for (const auto& s : steps) {
    TrackRow t;
    t.t_ns = t_ns;
    t.frame = static_cast<int32_t>(index);
    t.prev_frame = static_cast<int32_t>(from);
    t.u = static_cast<float>(s.px.x());
    t.v = static_cast<float>(s.px.y());
    t.intensity_prev = s.intensity_prev;
    t.intensity = s.intensity;
    diag_.tracks.push_back(t);
  }
}

void RunRecord::restart() {
  for (FrameRecord& f : frames_) {
    f.tracked = false;
    f.keyframe = false;
    f.ref_kf_id = -1;
    f.T_f_ref = SE3d();
    f.T_c_w = SE3d();
    f.affine = AffineBrightness();
  }
  keyframes_.clear();
  map_points_.clear();
  point_host_.clear();
  diag_.observations.clear();
  photometric_rows_.clear();
}

void RunRecord::takePoints(std::vector<MapPoint>* points) {
  if (provisional_) return;
  if (metric_) toMetric(&map_points_);
  if (points->empty()) {
    points->swap(map_points_);
  } else {
    points->insert(points->end(), map_points_.begin(), map_points_.end());
  }
  map_points_.clear();
  point_host_.clear();
}

void RunRecord::toMetric(std::vector<MapPoint>* points) const {
  for (size_t i = 0; i < points->size(); ++i) {
    const auto it = keyframes_.find(point_host_[i]);
    const RxSO3d T = transformOf(it != keyframes_.end() ? &it->second : nullptr);
    (*points)[i].p_w = (T * (*points)[i].p_w.cast<double>()).cast<float>();
  }
}

RxSO3d RunRecord::transformOf(const KeyframeRecord* r) const {
  // The first record from r on (kf_id order is time order) made after the scale settled: r's own
  // once it has; before, the first keyframe's at or after the settling time.
  const RxSO3d now = currentTransform();
  const int64_t t0 = std::max(r ? r->t_ns : std::numeric_limits<int64_t>::min(), settled_t_ns_);
  for (auto it = keyframes_.lower_bound(r ? r->kf_id : 0); it != keyframes_.end(); ++it)
    if (it->second.t_ns >= t0 && it->second.scale > 0) return RxSO3d(it->second.scale, now.so3());
  return now;
}

void RunRecord::recordFinal(Keyframe& kf) {
  observedTwist(kf);
  recordKeyframe(kf);
}

void RunRecord::recordKeyframe(const Keyframe& kf) {
  KeyframeRecord& r = keyframes_[kf.kf_id];
  r.kf_id = kf.kf_id;
  r.frame_index = kf.frame_index;
  r.t_ns = kf.t_ns;
  r.state = kf.state;
  r.time_offset_s = timeOffset();
  r.scale = scaleNow();
  r.line_delay_s = rolling_ ? timing_.line_delay_s : 0.0;
  if (rolling_) diag_.line_delay_s = timing_.line_delay_s;  // the log's header: the latest estimate
  if (!rolling_ && kf.has_observed_twist) r.state.twist = kf.observed_twist;
}

// Twist of a keyframe seen from the poses of its neighbouring frames (per second), for global-shutter
// runs where the state has none: the central difference of the previous and next tracked frames.
Vec6 RunRecord::observedTwist(Keyframe& kf) const {
  if (kf.has_observed_twist) return kf.observed_twist;
  const FrameRecord* prev = nullptr;
  const FrameRecord* next = nullptr;
  const FrameRecord* self = nullptr;
  for (const FrameRecord& f : frames_) {
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

void RunRecord::observationLeaves(const ActivePoint& p, const ActiveObservation& o) {
  if (o.state == ObsState::kOob) return;
  const Keyframe& host = *p.host;
  Keyframe& target = *o.target;
  ObservationRow r;
  r.t_ns = target.t_ns;
  r.frame = static_cast<int32_t>(target.frame_index);
  r.host = static_cast<int32_t>(host.frame_index);
  r.u = o.u;
  r.v = o.v;
  r.row = static_cast<float>(o.v - timing_.y0);
  const CameraCalibration& c = camera_.calibration();
  const double half_diag = 0.5 * std::hypot(c.width, c.height);
  r.radius = static_cast<float>(std::hypot(o.u - c.intrinsics[2], o.v - c.intrinsics[3]) / half_diag);
  r.host_radius = static_cast<float>(std::hypot(p.u - c.intrinsics[2], p.v - c.intrinsics[3]) / half_diag);
  r.intensity = p.pattern.color[kPatternCentre];
  r.grad_u = o.grad_u;
  r.grad_v = o.grad_v;
  // Pixel velocity d uv / dt = J_cam (xi_v + xi_w x P), P the point in the target camera.
  const Vec6 xi = rolling_ ? target.state.twist : observedTwist(target);
  Vec3 Z = p.bearing / p.idepth;
  if (rolling_) Z = SE3d::exp(-host.state.twist * timing_.rowTime(p.v)) * Z;
  const Vec3 X = host.state.T_c_w.inverse() * Z;
  const double t = timing_.rowTime(o.v);
  const Vec3 P = SE3d::exp(xi * t) * (target.state.T_c_w * X);
  Vec2 uv;
  Jac23 J;
  if (camera_.project(P, uv, &J)) {
    const Vec2 vel = J * (xi.head<3>() + xi.tail<3>().cross(P));
    r.vel_u = static_cast<float>(vel.x());
    r.vel_v = static_cast<float>(vel.y());
  }
  r.residual = o.mean_residual;
  r.weight = o.state == ObsState::kIn ? o.mean_weight : 0.f;  // an outlier: weight 0
  const double exp_ratio =
      (host.exposure_ms > 0 && target.exposure_ms > 0) ? target.exposure_ms / host.exposure_ms : 1.0;
  r.exposure_ratio =
      static_cast<float>(estimate_affine_ ? exp_ratio * std::exp(target.state.affine.a - host.state.affine.a) : 1.0);
  diag_.observations.push_back(r);
  if (keep_photometric_) photometric_rows_.push_back(r);
}

void RunRecord::pointLeaves(const ActivePoint& p) {
  const Vec3 X = pointInWorld(p, timing_, rolling_);
  if (!X.allFinite()) return;
  map_points_.push_back(MapPoint{X.cast<float>(), p.pattern.color[kPatternCentre]});
  point_host_.push_back(p.host ? p.host->kf_id : -1);
}

io::Trajectory RunRecord::frameTrajectory(const KeyframeList& window, std::vector<RxSO3d>* T_wm_wf) const {
  const bool map = T_wm_wf && metric_;
  std::vector<std::pair<io::StampedPose, RxSO3d>> poses;
  for (const FrameRecord& f : frames_) {
    if (!f.tracked) continue;
    SE3d T = f.T_c_w;
    const KeyframeRecord* ref = nullptr;
    const auto it = keyframes_.find(f.ref_kf_id);
    if (it != keyframes_.end()) {
      ref = &it->second;
      T = f.T_f_ref * ref->state.T_c_w;
    }
    bool in_window = false;
    // A keyframe still in the window: its current state.
    for (const auto& kf : window)
      if (kf->kf_id == f.ref_kf_id) {
        T = f.T_f_ref * kf->state.T_c_w;
        in_window = true;
      }
    poses.emplace_back(stamped(f.t_ns, T), map ? (in_window ? currentTransform() : transformOf(ref)) : RxSO3d());
  }
  // In time order, ties in record order. Indices are sorted, not the pairs: std::stable_sort's temporary
  // buffer (libstdc++ 12) ignores over-alignment, and RxSO3d needs 32 bytes with AVX (-march=native).
  std::vector<size_t> order(poses.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    return poses[a].first.t_ns != poses[b].first.t_ns ? poses[a].first.t_ns < poses[b].first.t_ns : a < b;
  });
  io::Trajectory t;
  t.frame = io::PoseFrame::kCamera;
  if (T_wm_wf) T_wm_wf->clear();
  for (size_t i : order) {
    t.poses.push_back(poses[i].first);
    if (map) T_wm_wf->push_back(poses[i].second);
  }
  return t;
}

io::Trajectory RunRecord::keyframeTrajectory(const KeyframeList& window, std::vector<RxSO3d>* T_wm_wf) const {
  const bool map = T_wm_wf && metric_;
  std::map<int64_t, std::pair<SE3d, RxSO3d>> by_time;
  for (const auto& [id, r] : keyframes_) by_time[r.t_ns] = {r.state.T_c_w, map ? transformOf(&r) : RxSO3d()};
  for (const auto& kf : window) by_time[kf->t_ns] = {kf->state.T_c_w, map ? currentTransform() : RxSO3d()};
  io::Trajectory t;
  t.frame = io::PoseFrame::kCamera;
  if (T_wm_wf) T_wm_wf->clear();
  for (const auto& [ts, TT] : by_time) {
    t.poses.push_back(stamped(ts, TT.first));
    if (map) T_wm_wf->push_back(TT.second);
  }
  return t;
}

std::vector<MapPoint> RunRecord::points(const KeyframeList& window) const {
  std::vector<MapPoint> out = map_points_;
  if (metric_) toMetric(&out);
  for (const auto& kf : window)
    for (const ActivePoint& p : kf->points) {
      const Vec3 X = pointInWorld(p, timing_, rolling_);
      if (!X.allFinite()) continue;
      const Vec3 P = metric_ ? Vec3(currentTransform() * X) : X;  // a window point: the current scale
      out.push_back(MapPoint{P.cast<float>(), p.pattern.color[kPatternCentre]});
    }
  return out;
}

std::vector<StateRow> RunRecord::states(const KeyframeList& window) const {
  std::map<int64_t, StateRow> rows;
  for (const auto& [id, r] : keyframes_) {
    StateRow s;
    s.t_ns = r.t_ns;
    s.twist = r.state.twist;
    s.v = r.state.v_wm;
    s.bg = r.state.bias_gyro;
    s.ba = r.state.bias_accel;
    s.time_offset_ms = 1e3 * r.time_offset_s;
    s.scale = r.scale;
    s.line_delay_us = 1e6 * r.line_delay_s;
    rows[r.t_ns] = s;
  }
  for (const auto& kf : window) {
    StateRow s;
    s.t_ns = kf->t_ns;
    s.twist = rolling_ ? kf->state.twist : (kf->has_observed_twist ? kf->observed_twist : Vec6::Zero());
    s.v = kf->state.v_wm;
    s.bg = kf->state.bias_gyro;
    s.ba = kf->state.bias_accel;
    s.time_offset_ms = 1e3 * timeOffset();
    s.scale = scaleNow();
    s.line_delay_us = rolling_ ? 1e6 * timing_.line_delay_s : 0.0;
    rows[kf->t_ns] = s;
  }
  std::vector<StateRow> out;
  for (const auto& [t, s] : rows) out.push_back(s);
  return out;
}

}  // namespace rsvio
