// Frame tracker: Levenberg-Marquardt per level, guesses, tracking-lost tests, keyframe indicators
// (contract in rsvio/frontend/frame_tracker.h).
#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <sstream>

#include "frame_tracker_internal.h"
#include "rsvio/core/error.h"

namespace rsvio {

namespace {

// DSO's increment scaling (SCALE_XI_TRANS = 0.5, SCALE_XI_ROT = 1, SCALE_A = 10, SCALE_B = 1000):
// the convergence test is on the increment in these units.
// The rate's increment counts as the rotation it makes over rate_time_s (half the readout).
double scaledNorm(const VecT& inc, double rate_time_s) {
  VecT s = inc;
  s.head<3>() /= 0.5;
  s(6) /= 10.0;
  s(7) /= 1000.0;
  s.tail<3>() *= rate_time_s;
  return s.norm();
}

std::string fmt(double v, int prec = 2) {
  std::ostringstream o;
  o.setf(std::ios::fixed);
  o.precision(prec);
  o << v;
  return o.str();
}

}  // namespace

bool FrameTracker::estimatesRate(const TrackingFrame& info) const {
  return info.estimate_rotation_rate && options_.rotation_rate_sigma > 0.0 && timing_.dtDv() != 0.0;
}

namespace {
constexpr int kRecentFrames = 10;  // TrackerOptions::max_poorly_explained counts over these
}  // namespace

void FrameTracker::accept(const TrackResult& result) {
  if (!result.ok()) return;
  last_explained_ = result.explained_ratio;
  recent_poor_ = (recent_poor_ << 1) | (result.poorly_explained ? 1u : 0u);
  last_rmse_ = result.level_rmse;
  if (std::isnan(first_rmse_)) first_rmse_ = result.level_rmse[0];
}

bool FrameTracker::keptPoorlyExplained(double explained_ratio) const {
  const int recent = __builtin_popcount(recent_poor_ & ((1u << kRecentFrames) - 1u));
  return options_.explained_keep_fraction > 0.0 && explained_ratio >= options_.min_explained_floor &&
         explained_ratio >= options_.explained_keep_fraction * last_explained_ &&  // false while NaN
         recent < options_.max_poorly_explained;
}

FrameTracker::Attempt FrameTracker::trackGuess(const ImagePyramid& frame, const TrackingFrame& info,
                                               const SE3d& guess, const std::array<double, 6>& abort_rmse) const {
  Attempt a;
  resetRows();  // every guess starts its row solves afresh: results do not depend on earlier guesses
  a.T_c_w = guess;
  a.affine = info.affine_guess;
  a.twist = info.twist;
  const double exposure_ratio = exposureRatio(ref_.exposure_ms, info.exposure_ms);
  const int coarsest = std::min(static_cast<int>(levels_.size()), frame.numLevels()) - 1;
  bool repeated = false;
  Linearization lin, lin_new;
  // Rolling shutter, TrackerOptions::rotation_rate_sigma: the twist's rotation is estimated too, with a
  // prior about the given rate; its weight in the energy's units is the level's mean energy per term
  // at the level's start (the residual variance) over sigma^2, energy sum w r^2 + lambda_w |w - w0|^2.
  const bool rate = estimatesRate(info);
  const Vec3 w_prior = info.twist.tail<3>();
  const double rate_time = 0.5 * std::abs(timing_.dtDv()) * std::max(1.0, 2.0 * timing_.y0);
  for (int lvl = coarsest; lvl >= 0; --lvl) {
    const ImageLevel& img = frame.level(lvl);
    double cutoff_mult = 1.0;
    evaluate(img, lvl, RsFrame{a.T_c_w, a.twist, info.w_dot}, a.affine, exposure_ratio, options_.cutoff_th, true, lin, rate);
    while (lin.saturatedRatio() > 0.6 && cutoff_mult < 50.0) {
      cutoff_mult *= 2.0;
      evaluate(img, lvl, RsFrame{a.T_c_w, a.twist, info.w_dot}, a.affine, exposure_ratio, options_.cutoff_th * cutoff_mult,
               true, lin, rate);
    }
    if (lin.num_points == 0) {
      a.failure = "no reference point in view on level " + std::to_string(lvl);
      return a;
    }
    double lambda = options_.lambda_initial;
    const double lambda_w = rate ? lin.meanEnergy() / (options_.rotation_rate_sigma * options_.rotation_rate_sigma) : 0.0;
    auto priorEnergy = [&](const Vec3& w) { return lambda_w * (w - w_prior).squaredNorm(); };
    auto totalMean = [&](const Linearization& l, const Vec3& w) {
      return l.num_terms > 0 ? (l.energy + priorEnergy(w)) / l.num_terms : std::nan("");
    };
    const int max_it = options_.max_iterations[static_cast<size_t>(std::min(lvl, 5))];
    for (int it = 0; it < max_it; ++it) {
      MatT Hl = lin.H;
      for (int i = 0; i < kTrackDim; ++i) Hl(i, i) *= (1.0 + lambda);
      VecT bl = lin.b;
      if (rate) {
        Hl.bottomRightCorner<3, 3>().diagonal().array() += lambda_w;
        bl.tail<3>() += lambda_w * (a.twist.tail<3>() - w_prior);
      }
      // Fixed brightness parameters (and a fixed rate): drop their rows and columns.
      int dim = 6;
      int idx[kTrackDim] = {0, 1, 2, 3, 4, 5, -1, -1, -1, -1, -1};
      if (options_.estimate_a) idx[dim++] = 6;
      if (options_.estimate_b) idx[dim++] = 7;
      if (rate)
        for (int k = 8; k < kTrackDim; ++k) idx[dim++] = k;
      Eigen::MatrixXd Hr(dim, dim);
      Eigen::VectorXd br(dim);
      for (int i = 0; i < dim; ++i) {
        br(i) = bl(idx[i]);
        for (int j = 0; j < dim; ++j) Hr(i, j) = Hl(idx[i], idx[j]);
      }
      const Eigen::VectorXd xr = Hr.ldlt().solve(-br);
      VecT inc = VecT::Zero();
      for (int i = 0; i < dim; ++i) inc(idx[i]) = xr(i);
      // DSO's extrapolation when lambda is small: a slightly longer step.
      if (lambda < 1e-3) inc *= std::sqrt(std::sqrt(1e-3 / lambda));
      if (!inc.allFinite()) inc.setZero();

      const SE3d T_new = SE3d::exp(inc.head<6>()) * a.T_c_w;
      AffineBrightness aff_new = a.affine;
      aff_new.a += inc(6);
      aff_new.b += inc(7);
      Vec6 twist_new = a.twist;
      twist_new.tail<3>() += inc.tail<3>();
      evaluate(img, lvl, RsFrame{T_new, twist_new, info.w_dot}, aff_new, exposure_ratio, options_.cutoff_th * cutoff_mult, true,
               lin_new, rate);
      ++a.iterations;
      const bool accept = lin_new.num_terms > 0 && totalMean(lin_new, twist_new.tail<3>()) < totalMean(lin, a.twist.tail<3>());
      if (accept) {
        std::swap(lin, lin_new);
        a.T_c_w = T_new;
        a.affine = aff_new;
        a.twist = twist_new;
        lambda *= 0.5;
      } else {
        lambda *= 4.0;
        if (lambda < 1e-3) lambda = 1e-3;
      }
      if (!(scaledNorm(inc, rate_time) > options_.converge_eps)) break;
    }
    a.level_rmse[static_cast<size_t>(lvl)] = std::sqrt(lin.meanEnergy());
    if (a.level_rmse[static_cast<size_t>(lvl)] > options_.abort_factor * abort_rmse[static_cast<size_t>(lvl)]) {
      a.failure = "worse than an earlier guess on level " + std::to_string(lvl);
      return a;
    }
    // DSO repeats a level once when it had to raise the cutoff (the start was poor).
    if (cutoff_mult > 1.0 && !repeated) {
      ++lvl;
      repeated = true;
    }
    // The rate through the pose reached, for the next level solved, lvl - 1 (a finer one, or this one
    // again when DSO repeats it): TrackerOptions::twist_refresh_levels.
    if (lvl >= 1 && lvl <= options_.twist_refresh_levels && info.rotation_rate_of_pose) {
      const Vec3 w = info.rotation_rate_of_pose(a.T_c_w);
      if (w.allFinite()) a.twist.tail<3>() = w;
    }
  }
  a.ok = std::isfinite(a.level_rmse[0]) && a.T_c_w.translation().allFinite();
  if (!a.ok) a.failure = "diverged";
  return a;
}

TrackResult FrameTracker::track(const ImagePyramid& frame, const TrackingFrame& info,
                                const std::vector<SE3d>& guesses_in) {
  if (!hasReference()) throw Error("FrameTracker::track: no reference keyframe (call setReference first)");
  if (frame.width() != ref_.pyramid->width() || frame.height() != ref_.pyramid->height())
    throw Error("FrameTracker::track: frame size differs from the reference keyframe's");
  const std::vector<SE3d> guesses = guesses_in.empty() ? std::vector<SE3d>{ref_.T_c_w} : guesses_in;

  TrackResult res;
  std::array<double, 6> achieved;
  achieved.fill(std::nan(""));
  Attempt best;
  bool have_best = false;
  std::string last_failure;
  for (size_t g = 0; g < guesses.size(); ++g) {
    const Attempt a = trackGuess(frame, info, guesses[g], achieved);
    ++res.guesses_tried;
    res.iterations += a.iterations;
    if (a.ok && (!have_best || a.level_rmse[0] < best.level_rmse[0])) {
      best = a;
      have_best = true;
      res.guess_index = static_cast<int>(g);
    }
    if (!a.ok) last_failure = a.failure;
    if (have_best)
      for (size_t l = 0; l < achieved.size(); ++l)
        if (std::isfinite(a.level_rmse[l]) && !(achieved[l] <= a.level_rmse[l])) achieved[l] = a.level_rmse[l];
    if (have_best && best.level_rmse[0] < options_.retrack_factor * last_rmse_[0]) break;
  }

  if (!have_best) {
    res.status = TrackResult::Status::Lost;
    res.reason = "no guess converged (" + std::to_string(res.guesses_tried) + " tried; last: " + last_failure + ")";
    res.T_c_w = guesses.front();
    res.affine = info.affine_guess;
    res.level_rmse.fill(std::nan(""));
    return res;
  }
  res.T_c_w = best.T_c_w;
  res.affine = best.affine;
  res.twist = best.twist;
  res.rate_estimated = estimatesRate(info);
  res.level_rmse = best.level_rmse;

  // Lost tests on the winner, at level 0 with the base cutoff and its twist.
  TrackingFrame info_best = info;
  info_best.twist = best.twist;
  const LevelEnergy e = levelEnergy(frame, info_best, 0, best.T_c_w, best.affine);
  res.rmse = e.rmse();
  res.num_points = e.num_points;
  res.inlier_ratio = e.num_terms > 0 ? 1.0 - static_cast<double>(e.num_saturated) / e.num_terms : 0.0;
  res.explained_ratio = e.num_points > 0 ? static_cast<double>(e.num_explained) / e.num_points : 0.0;
  const double log_alpha = std::log(exposureRatio(ref_.exposure_ms, info.exposure_ms)) + best.affine.a - ref_.affine.a;
  res.status = TrackResult::Status::Lost;
  if (e.num_points < options_.min_points) {
    res.reason = "only " + std::to_string(e.num_points) + " reference points in view (min " +
                 std::to_string(options_.min_points) + ")";
  } else if (res.inlier_ratio < options_.min_inlier_ratio) {
    res.reason = "inlier ratio " + fmt(res.inlier_ratio) + " below " + fmt(options_.min_inlier_ratio) +
                 " (rmse " + fmt(res.rmse) + ")";
  } else if (!(res.rmse <= options_.max_rmse)) {
    res.reason = "rmse " + fmt(res.rmse) + " above " + fmt(options_.max_rmse);
  } else if (!(res.explained_ratio >= options_.min_explained_ratio) && !keptPoorlyExplained(res.explained_ratio)) {
    res.reason = "explained ratio " + fmt(res.explained_ratio) + " below " + fmt(options_.min_explained_ratio) +
                 " (points in view whose residual RMS is below " + fmt(options_.explained_residual) +
                 " x their pattern's intensity spread; the last tracked frame's " + fmt(last_explained_) + ")";
  } else if ((options_.estimate_a && std::abs(log_alpha) > options_.max_abs_log_alpha) ||
             (options_.estimate_b && std::abs(best.affine.b) > options_.max_abs_b)) {
    res.reason = "brightness change out of range (log gain " + fmt(log_alpha) + ", b " + fmt(best.affine.b) + ")";
  } else {
    res.status = TrackResult::Status::Ok;
    res.poorly_explained = !(res.explained_ratio >= options_.min_explained_ratio);
  }

  // DSO's flow indicators on the level-0 points, central poses.
  const LevelPoints& L0 = *levels_[0];
  if (L0.n > 0) {
    const SE3d T_t_h = best.T_c_w * ref_.T_c_w.inverse();
    Eigen::Matrix3Xd P(3, 2 * L0.n);
    for (int i = 0; i < L0.n; ++i) {
      const Vec3& Xh = L0.host_point[static_cast<size_t>(i)];
      P.col(2 * i) = T_t_h * Xh;
      P.col(2 * i + 1) = Xh + T_t_h.translation();
    }
    Eigen::Matrix2Xd uv;
    std::vector<uint8_t> valid;
    camera_.project(P, uv, valid, nullptr);
    double srt = 0, st = 0;
    int n = 0;
    for (int i = 0; i < L0.n; ++i) {
      if (!valid[static_cast<size_t>(2 * i)] || !valid[static_cast<size_t>(2 * i + 1)]) continue;
      srt += (uv.col(2 * i) - L0.host_uv0[static_cast<size_t>(i)]).squaredNorm();
      st += (uv.col(2 * i + 1) - L0.host_uv0[static_cast<size_t>(i)]).squaredNorm();
      ++n;
    }
    if (n > 0) {
      res.flow_rt_px = std::sqrt(srt / n);
      res.flow_t_px = std::sqrt(st / n);
    }
  }
  return res;
}

ParamTable TrackerOptions::paramTable() {
  const TrackerOptions d;
  return {
      paramInt("track_levels", d.max_levels, 1, 6, "", "pyramid levels used by the tracker (coarsest = levels - 1)"),
      paramDouble("track_cutoff", d.cutoff_th, 1.0, 255.0, "intensity",
                  "residuals above this count as saturated in tracking (DSO: 20)"),
      paramDouble("track_retrack_factor", d.retrack_factor, 1.0, 100.0, "",
                  "stop trying guesses once the RMSE is below this x the last frame's (DSO: 1.5)"),
      paramDouble("track_abort_factor", d.abort_factor, 1.0, 100.0, "",
                  "drop a guess on a level where its RMSE exceeds this x the best so far (DSO: 1.5)"),
      paramInt("track_min_points", d.min_points, 1, 100000, "", "fewer reference points in view: tracking lost"),
      paramDouble("track_min_inlier_ratio", d.min_inlier_ratio, 0.0, 1.0, "",
                  "lower share of pattern pixels below the cutoff: tracking lost"),
      paramDouble("track_max_rmse", d.max_rmse, 0.1, 1000.0, "intensity", "higher level-0 RMSE: tracking lost"),
      paramDouble("track_min_explained_ratio", d.min_explained_ratio, 0.0, 1.0, "",
                  "lower share of the points in view whose residual RMS is below half their pattern's "
                  "intensity spread: tracking lost"),
      paramDouble("track_explained_keep_fraction", d.explained_keep_fraction, 0.0, 1.0, "",
                  "a frame below track_min_explained_ratio is kept when its ratio is at least this x the last "
                  "tracked frame's (a model lacking an effect explains every frame less; a wrong pose drops at "
                  "once; 0: never kept)"),
      paramDouble("track_min_explained_floor", d.min_explained_floor, 0.0, 1.0, "",
                  "no frame with a lower explained ratio is kept (track_explained_keep_fraction)"),
      paramInt("track_max_poorly_explained", d.max_poorly_explained, 0, 10, "",
               "no frame is kept poorly explained when this many of the last 10 tracked frames were"),
      paramInt("track_twist_retries", d.twist_retries, 0, 5, "",
               "rolling shutter: a frame lost with its predicted twist is tracked again this many times at most, "
               "with the twist's rotation re-estimated from the pose each attempt reached (0: never)"),
      paramInt("track_twist_refinements", d.twist_refinements, 0, 5, "",
               "rolling shutter: a tracked frame is tracked again this many times from the pose it reached, with "
               "the twist's rotation re-estimated as the rate through that pose (0: never; not when the IMU "
               "gives the rotation)"),
      paramDouble("track_rotation_rate_sigma", d.rotation_rate_sigma, 0.0, 100.0, "rad/s",
                  "rolling shutter: > 0 estimates the twist's rotation with the pose under a prior of this sigma about "
                  "the predicted rate (0: the twist is held fixed)"),
      paramInt("track_twist_refresh_levels", d.twist_refresh_levels, 0, 5, "",
               "rolling shutter: within each pass the twist's rotation is re-estimated as the rate through the "
               "pose reached before each solve of the pyramid levels below this number (0: never; 1: before level 0; "
               "not when the IMU gives the rotation)"),
  };
}

TrackerOptions TrackerOptions::fromParams(const Params& p) {
  TrackerOptions o;
  o.max_levels = static_cast<int>(p.getInt("track_levels"));
  o.cutoff_th = p.getDouble("track_cutoff");
  o.retrack_factor = p.getDouble("track_retrack_factor");
  o.abort_factor = p.getDouble("track_abort_factor");
  o.min_points = static_cast<int>(p.getInt("track_min_points"));
  o.min_inlier_ratio = p.getDouble("track_min_inlier_ratio");
  o.max_rmse = p.getDouble("track_max_rmse");
  o.min_explained_ratio = p.getDouble("track_min_explained_ratio");
  o.explained_keep_fraction = p.getDouble("track_explained_keep_fraction");
  o.min_explained_floor = p.getDouble("track_min_explained_floor");
  o.max_poorly_explained = static_cast<int>(p.getInt("track_max_poorly_explained"));
  o.twist_retries = static_cast<int>(p.getInt("track_twist_retries"));
  o.twist_refinements = static_cast<int>(p.getInt("track_twist_refinements"));
  o.twist_refresh_levels = static_cast<int>(p.getInt("track_twist_refresh_levels"));
  o.rotation_rate_sigma = p.getDouble("track_rotation_rate_sigma");
  return o;
}

}  // namespace rsvio
