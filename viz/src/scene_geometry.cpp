// Scene geometry from a snapshot (scene_geometry.h).
#include "scene_geometry.h"

#include <algorithm>
#include <cmath>

namespace rsvio::viz::detail {
namespace {

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  const size_t k = static_cast<size_t>(std::clamp(p, 0.0, 1.0) * (v.size() - 1));
  std::nth_element(v.begin(), v.begin() + k, v.end());
  return v[k];
}

}  // namespace

SceneGeometry buildSceneGeometry(const io::Snapshot& s, bool points, bool frusta, bool ground_truth, int max_frusta) {
  SceneGeometry g;
  const bool aligned = s.errors.has_value();
  const eval::Alignment A = aligned ? s.errors->alignment : eval::Alignment{};
  const io::Trajectory& dense = s.trajectory.empty() ? s.keyframes : s.trajectory;

  if (aligned && !s.errors->frames.empty()) {
    for (const auto& e : s.errors->frames) {
      g.est.push_back(e.p_est_aligned);
      g.est_err.push_back(e.err_m);
      g.err_max = std::max(g.err_max, e.err_m);
    }
    if (!(g.err_max > 0)) g.err_max = 1e-3;
    const char* mode = A.mode == eval::AlignMode::kSim3 ? "Sim(3)" : A.mode == eval::AlignMode::kSE3 ? "SE(3)" : "no";
    g.align_label = std::string(mode) + " alignment on " + s.errors->aligned_on;
  } else {
    for (const auto& p : dense.poses) {
      g.est.push_back(p.p_W_X);
      g.est_err.push_back(std::nan(""));
    }
    g.align_label = "not aligned (no ground truth)";
  }
  if (aligned && ground_truth) {
    // Only the stretch of ground truth the estimate covers (plus a little), so a short run is not lost
    // in a long ground-truth file.
    const int64_t t0 = s.errors->frames.empty() ? INT64_MIN : s.errors->frames.front().t_ns - 1'000'000'000;
    const int64_t t1 = s.errors->frames.empty() ? INT64_MAX : s.errors->frames.back().t_ns + 1'000'000'000;
    for (const auto& p : s.ground_truth.poses) {
      if (p.t_ns >= t0 && p.t_ns <= t1) g.gt.push_back(p.p_W_X);
    }
  }
  g.unit = (aligned || s.poseFrame() == io::PoseFrame::kBody) ? "m" : "units";

  // The trajectory views frame the trajectory (estimate and the ground truth it covers), not the room:
  // a point cloud ten times the path's size would make the path a smear in a corner.
  g.bounds.setEmpty();
  for (const auto& p : g.est) g.bounds.extend(p);
  for (const auto& p : g.gt) g.bounds.extend(p);
  const bool have_path = !g.bounds.isEmpty();
  const double path_extent = have_path ? std::max(1e-3, g.bounds.sizes().maxCoeff()) : 0.0;
  if (have_path) {
    const Eigen::Vector3d grow = Eigen::Vector3d::Constant(0.5 * path_extent);
    g.near_bounds = Eigen::AlignedBox3d(g.bounds.min() - grow, g.bounds.max() + grow);
  }
  g.scene_bounds = g.bounds;

  if (points && !s.points.empty()) {
    std::vector<double> inten;
    for (float v : s.points.intensity) {
      if (std::isfinite(v)) inten.push_back(v);
    }
    const double lo = percentile(inten, 0.02), hi = percentile(inten, 0.98);
    std::vector<double> xs, ys, zs;
    for (size_t i = 0; i < s.points.size(); ++i) {
      const Eigen::Vector3d p = aligned ? A.apply(s.points.p_W[i]) : s.points.p_W[i];
      if (!p.allFinite()) continue;
      g.points.push_back(p);
      g.point_near.push_back(!have_path || g.near_bounds.contains(p));
      const double v = s.points.intensity[i];
      g.point_shade.push_back(std::isfinite(v) ? (hi > lo ? std::clamp((v - lo) / (hi - lo), 0.0, 1.0) : 0.5) : 0.5);
      xs.push_back(p.x());
      ys.push_back(p.y());
      zs.push_back(p.z());
    }
    // The overview frames the bulk of the cloud, not its outliers (far points of a direct method are common).
    if (g.points.size() >= 20) {
      g.scene_bounds.extend(Eigen::Vector3d(percentile(xs, 0.05), percentile(ys, 0.05), percentile(zs, 0.05)));
      g.scene_bounds.extend(Eigen::Vector3d(percentile(xs, 0.95), percentile(ys, 0.95), percentile(zs, 0.95)));
    } else {
      for (const auto& p : g.points) g.scene_bounds.extend(p);
    }
    if (!have_path) g.bounds = g.scene_bounds, g.near_bounds = g.scene_bounds;
  }

  const double extent = g.bounds.isEmpty() ? 1.0 : std::max(1e-3, g.bounds.sizes().maxCoeff());
  // Frusta sized to the path: a few percent of its extent, and no deeper than the typical distance
  // between two drawn keyframes, so they mark the keyframes without hiding the line.
  g.frustum_size = 0.03 * extent;
  if (frusta && !s.keyframes.empty()) {
    const size_t n = s.keyframes.size();
    const size_t step = max_frusta > 0 && n > static_cast<size_t>(max_frusta) ? (n + max_frusta - 1) / max_frusta : 1;
    const bool body = s.keyframes.frame == io::PoseFrame::kBody;
    for (size_t i = 0; i < n; i += step) {
      const auto& kp = s.keyframes.poses[i];
      Eigen::Isometry3d T_W_X = Eigen::Isometry3d::Identity();
      T_W_X.linear() = kp.q_W_X.normalized().toRotationMatrix();
      T_W_X.translation() = kp.p_W_X;
      const Eigen::Isometry3d T_W_C = (body && s.T_B_C) ? T_W_X * *s.T_B_C : T_W_X;
      Frustum f;
      f.R_W_C = A.R * T_W_C.linear();
      f.p_W_C = A.apply(T_W_C.translation());
      if (f.p_W_C.allFinite()) g.frusta.push_back(f);
    }
    std::vector<double> gaps;
    for (size_t i = 1; i < g.frusta.size(); ++i) gaps.push_back((g.frusta[i].p_W_C - g.frusta[i - 1].p_W_C).norm());
    const double gap = percentile(gaps, 0.5);
    if (gap > 0) g.frustum_size = std::min(g.frustum_size, 0.5 * gap);
    g.frustum_size = std::max(g.frustum_size, 0.01 * extent);
  }
  if (g.empty()) {
    if (s.failed()) g.message = "run failed" + (s.summary.error.empty() ? std::string() : ": " + s.summary.error);
    else g.message = "nothing to draw: no trajectory, ground truth or points in " + s.run_dir;
  }
  return g;
}

}  // namespace rsvio::viz::detail
