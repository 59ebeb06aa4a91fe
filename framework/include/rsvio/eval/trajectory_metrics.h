// Trajectory error metrics: absolute trajectory error (ATE), relative pose error (RPE) and error over
// time, computed on associated pose pairs after alignment.
//
// Contract:
// - Inputs are T_W_X poses of the same frame X (map ground truth to camera poses first when the estimate
//   is of the camera: eval/extrinsic.h). Positions in metres; angles reported in degrees.
// - Association: associateNearest (eval/association.h), every estimate to the nearest ground-truth stamp
//   within options.max_dt_ns.
// - ATE (the paper's eq. 35 with SE(3)): alignment from the positions of all pairs (eval/alignment.h),
//   then per pair e_i = |p_gt_i - (s R p_est_i + t)|; reported as RMSE, mean, median, max, min, std.
//   The rotation part is the angle of R_gt_i^T (R R_est_i), reported alongside.
// - RPE: for pairs (i, j) of associated poses, E = (G_i^-1 G_j)^-1 (A_i^-1 A_j) with G ground truth and
//   A the aligned estimate (only the scale matters: the rigid part cancels); translation error |t(E)|
//   and rotation error angle(E). Every associated pose i starts one pair; j is the first pose at or
//   beyond the step:
//     * distance steps: ground-truth path length (summed over ALL ground-truth poses between the two
//       matched stamps, so gaps in the estimate do not shorten it) >= d; `drift_percent` = |t(E)| / d;
//     * time steps: t_j - t_i >= dt.
//   A pair whose step overshoots 1.5x the requested one (a gap in the estimate) is skipped.
//   Distance steps are fractions of the associated ground-truth path length (default 1, 2, 5, 10 %)
//   and/or fixed metres; time steps are seconds. A step with no pair is reported with pairs = 0.
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "rsvio/eval/alignment.h"
#include "rsvio/eval/association.h"
#include "rsvio/io/trajectory.h"

namespace rsvio::eval {

struct ErrorStats {
  size_t n = 0;
  double rmse = 0, mean = 0, median = 0, max = 0, min = 0, std = 0;
};
ErrorStats computeStats(std::vector<double> values);  // all zero when empty

struct RpeStep {
  enum class Kind { kDistance, kTime };
  Kind kind = Kind::kDistance;
  double value = 0;            // metres or seconds
  double path_fraction = 0;    // > 0 when the distance came from a fraction of the path length
};

struct RpeResult {
  RpeStep step;
  size_t pairs = 0;
  ErrorStats trans_m;
  ErrorStats rot_deg;
  double drift_percent_mean = 0;  // distance steps only: mean of 100 * |t(E)| / d
};

struct ErrorSample {
  int64_t t_ns = 0;  // estimate stamp
  int64_t dt_ns = 0; // t_gt - t_est of the pair
  double trans_err_m = 0;
  double rot_err_deg = 0;
  Eigen::Vector3d p_est_aligned = Eigen::Vector3d::Zero();
  Eigen::Vector3d p_gt = Eigen::Vector3d::Zero();
};

struct EvalOptions {
  AlignMode align = AlignMode::kSE3;
  int64_t max_dt_ns = 10'000'000;  // 0.01 s
  std::vector<double> rpe_path_fractions = {0.01, 0.02, 0.05, 0.10};
  std::vector<double> rpe_distances_m;               // fixed distances, in addition
  std::vector<double> rpe_windows_s = {0.5, 1.0, 2.0, 5.0};
};

struct EvalResult {
  Association association;
  Alignment alignment;
  ErrorStats ate_m;
  ErrorStats ate_rot_deg;
  std::vector<RpeResult> rpe;
  std::vector<ErrorSample> over_time;
  double gt_path_length_m = 0;  // ground-truth path between the first and last matched stamps
  double duration_s = 0;        // first to last associated estimate
};

// Throws rsvio::Error when no pair is associated or alignment is degenerate; the message says why.
EvalResult evaluateTrajectory(const io::Trajectory& gt, const io::Trajectory& est, const EvalOptions& options);

// Relative pose error on already-associated, already-aligned poses (exposed for tests).
// gt_path_m[i] is the cumulative ground-truth path length at pair i.
RpeResult computeRpe(const std::vector<io::StampedPose>& gt, const std::vector<io::StampedPose>& est_aligned,
                     const std::vector<double>& gt_path_m, const RpeStep& step);

}  // namespace rsvio::eval
