// Alignment of an estimated trajectory's positions to ground truth (Umeyama 1991, "Least-squares
// estimation of transformation parameters between two point patterns", eq. 40-42).
//
// Finds s, R, t minimising sum_i |p_gt_i - (s R p_est_i + t)|^2 over paired positions:
// - kSE3: s fixed to 1 (metric estimates, e.g. VIO; the paper's eq. 35 minimises over SE(3)),
// - kSim3: s free (monocular VO, whose scale is arbitrary),
// - kNone: identity (the estimate is already in the ground truth's world frame).
// The result maps estimate-world points into the ground-truth world: p_gt ~ s * R * p_est + t.
// Plain Eigen on purpose: evaluation must not depend on the estimator's Lie module it checks.
#pragma once
#include <Eigen/Core>
#include <string>

namespace rsvio::eval {

enum class AlignMode { kNone, kSE3, kSim3 };

const char* alignModeName(AlignMode m);  // "none", "se3", "sim3"
// "none" | "se3" | "sim3" (case-insensitive); throws ConfigError naming the option otherwise.
AlignMode parseAlignMode(const std::string& text, const std::string& option_name = "--align");

struct Alignment {
  AlignMode mode = AlignMode::kNone;
  double scale = 1.0;
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();

  Eigen::Vector3d apply(const Eigen::Vector3d& p_est) const { return scale * (R * p_est) + t; }
};

// src and dst are 3xN with N >= 3 for kSE3/kSim3 (N >= 1 for kNone). Throws rsvio::Error when the
// problem is degenerate (too few pairs, all estimate positions equal for kSim3).
Alignment umeyamaAlignment(const Eigen::Matrix3Xd& p_est, const Eigen::Matrix3Xd& p_gt, AlignMode mode);

}  // namespace rsvio::eval
