// ATE, RPE and error over time (definitions in rsvio/eval/trajectory_metrics.h).
#include "rsvio/eval/trajectory_metrics.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "rsvio/core/error.h"
#include "rsvio/core/time.h"

namespace rsvio::eval {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;
// A pair whose step overshoots the requested one by more than this factor spans a gap: skipped.
constexpr double kMaxOvershoot = 1.5;

double angleDeg(const Eigen::Quaterniond& q) {
  // Robust near 0 and pi: 2 atan2(|v|, |w|).
  return 2.0 * std::atan2(q.vec().norm(), std::abs(q.w())) * kRadToDeg;
}

std::string fmtMs(int64_t ns) { return std::to_string(static_cast<double>(ns) * 1e-6) + " ms"; }

}  // namespace

ErrorStats computeStats(std::vector<double> v) {
  ErrorStats s;
  s.n = v.size();
  if (v.empty()) return s;
  double sum = 0, sum_sq = 0;
  for (double x : v) {
    sum += x;
    sum_sq += x * x;
  }
  const double n = static_cast<double>(v.size());
  s.mean = sum / n;
  s.rmse = std::sqrt(sum_sq / n);
  s.std = std::sqrt(std::max(0.0, sum_sq / n - s.mean * s.mean));
  const auto [mn, mx] = std::minmax_element(v.begin(), v.end());
  s.min = *mn;
  s.max = *mx;
  std::sort(v.begin(), v.end());
  const size_t m = v.size() / 2;
  s.median = v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
  return s;
}

RpeResult computeRpe(const std::vector<io::StampedPose>& gt, const std::vector<io::StampedPose>& est,
                     const std::vector<double>& gt_path_m, const RpeStep& step) {
  RpeResult r;
  r.step = step;
  const size_t n = gt.size();
  if (step.value <= 0 || n < 2) return r;
  std::vector<double> et, er, drift;
  const bool by_distance = step.kind == RpeStep::Kind::kDistance;
  size_t j = 0;
  for (size_t i = 0; i < n; ++i) {
    // j only moves forward: both the path length and the stamps are non-decreasing in i.
    j = std::max(j, i + 1);
    auto span = [&](size_t k) {
      return by_distance ? gt_path_m[k] - gt_path_m[i] : nsToS(est[k].t_ns - est[i].t_ns);
    };
    while (j < n && span(j) < step.value) ++j;
    if (j >= n) break;
    if (span(j) > kMaxOvershoot * step.value) continue;
    const Eigen::Quaterniond dq_gt = gt[i].q_W_X.conjugate() * gt[j].q_W_X;
    const Eigen::Vector3d dp_gt = gt[i].q_W_X.conjugate() * (gt[j].p_W_X - gt[i].p_W_X);
    const Eigen::Quaterniond dq_est = est[i].q_W_X.conjugate() * est[j].q_W_X;
    const Eigen::Vector3d dp_est = est[i].q_W_X.conjugate() * (est[j].p_W_X - est[i].p_W_X);
    // E = (G_i^-1 G_j)^-1 (A_i^-1 A_j): rotation dq_gt^-1 dq_est, translation dq_gt^-1 (dp_est - dp_gt).
    const Eigen::Quaterniond dq_err = dq_gt.conjugate() * dq_est;
    const Eigen::Vector3d dp_err = dq_gt.conjugate() * (dp_est - dp_gt);
    et.push_back(dp_err.norm());
    er.push_back(angleDeg(dq_err));
    if (by_distance) drift.push_back(100.0 * dp_err.norm() / step.value);
  }
  r.pairs = et.size();
  r.trans_m = computeStats(et);
  r.rot_deg = computeStats(er);
  r.drift_percent_mean = drift.empty() ? 0.0 : std::accumulate(drift.begin(), drift.end(), 0.0) / drift.size();
  return r;
}

EvalResult evaluateTrajectory(const io::Trajectory& gt, const io::Trajectory& est, const EvalOptions& opt) {
  const std::string what = (est.source.empty() ? std::string("estimate") : est.source) + " vs " +
                           (gt.source.empty() ? std::string("ground truth") : gt.source);
  if (gt.empty()) throw Error(what + ": the ground truth has no poses");
  if (est.empty()) throw Error(what + ": the estimate has no poses");
  EvalResult r;
  r.association = associateNearest(est, gt, opt.max_dt_ns);
  const auto& pairs = r.association.pairs;
  if (pairs.empty()) {
    throw Error(what + ": no estimate is within " + fmtMs(opt.max_dt_ns) +
                " of a ground-truth stamp (check the time base: seconds vs nanoseconds, or raise --max-dt)");
  }
  const size_t n = pairs.size();
  Eigen::Matrix3Xd pe(3, n), pg(3, n);
  for (size_t k = 0; k < n; ++k) {
    pe.col(k) = est.poses[pairs[k].i_est].p_W_X;
    pg.col(k) = gt.poses[pairs[k].i_gt].p_W_X;
  }
  r.alignment = umeyamaAlignment(pe, pg, opt.align);
  const Eigen::Quaterniond q_align(r.alignment.R);

  // Cumulative ground-truth path over every ground-truth pose, so gaps in the estimate do not shorten it.
  std::vector<double> gt_cum(gt.size(), 0.0);
  for (size_t k = 1; k < gt.size(); ++k) gt_cum[k] = gt_cum[k - 1] + (gt.poses[k].p_W_X - gt.poses[k - 1].p_W_X).norm();

  std::vector<io::StampedPose> g(n), a(n);
  std::vector<double> path(n), et(n), er(n);
  r.over_time.resize(n);
  for (size_t k = 0; k < n; ++k) {
    g[k] = gt.poses[pairs[k].i_gt];
    a[k] = est.poses[pairs[k].i_est];
    a[k].p_W_X = r.alignment.apply(a[k].p_W_X);
    a[k].q_W_X = (q_align * a[k].q_W_X).normalized();
    path[k] = gt_cum[pairs[k].i_gt];
    et[k] = (g[k].p_W_X - a[k].p_W_X).norm();
    er[k] = angleDeg(g[k].q_W_X.conjugate() * a[k].q_W_X);
    r.over_time[k] = {a[k].t_ns, pairs[k].dt_ns, et[k], er[k], a[k].p_W_X, g[k].p_W_X};
  }
  r.ate_m = computeStats(et);
  r.ate_rot_deg = computeStats(er);
  r.gt_path_length_m = path.back() - path.front();
  r.duration_s = nsToS(a.back().t_ns - a.front().t_ns);

  for (double f : opt.rpe_path_fractions) {
    if (r.gt_path_length_m > 0) r.rpe.push_back(computeRpe(g, a, path, {RpeStep::Kind::kDistance, f * r.gt_path_length_m, f}));
  }
  for (double d : opt.rpe_distances_m) r.rpe.push_back(computeRpe(g, a, path, {RpeStep::Kind::kDistance, d, 0.0}));
  for (double w : opt.rpe_windows_s) r.rpe.push_back(computeRpe(g, a, path, {RpeStep::Kind::kTime, w, 0.0}));
  return r;
}

}  // namespace rsvio::eval
