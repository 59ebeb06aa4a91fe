// Private types of FrameTracker shared by frame_tracker.cpp and frame_tracker_solve.cpp.
#pragma once
#include <Eigen/Core>
#include <cmath>
#include <vector>

#include "rsvio/frontend/block_runner.h"
#include "rsvio/frontend/frame_tracker.h"
#include "rsvio/interfaces/camera.h"
#include "rsvio/lie/se3.h"

namespace rsvio {

// Points per block of the deterministic parallel sums (fixed: results do not depend on threads).
constexpr int kBlockPoints = 128;

// The tracker's unknowns: left pose increment (6; translation, rotation), affine a, b, and with
// TrackerOptions::rotation_rate_sigma > 0 the twist's rotation (3, rad/s).
constexpr int kTrackDim = 11;
using MatT = Eigen::Matrix<double, kTrackDim, kTrackDim>;
using VecT = Eigen::Matrix<double, kTrackDim, 1>;

// Rolling-shutter row solve in the tracker: tolerance and iteration cap (rs_projection.h's method).
constexpr double kRowLinearStepPx = 0.05;  // Newton steps below this are applied linearly (see projectBlock)
constexpr int kRowMaxIterations = 10;

// Normal equations of (delta(6), a, b, dw(3)) on one level, with energy statistics (the dw block
// stays zero unless the rate is estimated).
struct FrameTracker::Linearization {
  MatT H = MatT::Zero();
  VecT b = VecT::Zero();
  double energy = 0.0;
  int num_terms = 0;
  int num_saturated = 0;
  int num_points = 0;
  int num_explained = 0;  // only counted by residual passes (linearize = false): the lost test

  void setZero() {
    H.setZero();
    b.setZero();
    energy = 0.0;
    num_terms = num_saturated = num_points = num_explained = 0;
  }
  void add(const Linearization& o) {
    H += o.H;
    b += o.b;
    energy += o.energy;
    num_terms += o.num_terms;
    num_saturated += o.num_saturated;
    num_points += o.num_points;
    num_explained += o.num_explained;
  }
  double meanEnergy() const { return num_terms > 0 ? energy / num_terms : std::nan(""); }
  double saturatedRatio() const { return num_terms > 0 ? static_cast<double>(num_saturated) / num_terms : 1.0; }
};

// A block of reference points with its own scratch buffers and partial sums.
struct FrameTracker::Block {
  int begin = 0;                  // index of the first point of the level
  Eigen::Matrix3Xd X_w;           // world points
  // scratch, reused across evaluations (no allocation in steady state)
  Eigen::Matrix3Xd P0, P;         // points in the target at t = 0, at the row time
  Eigen::Matrix2Xd uv, uv_a;      // projections (all points / the active ones of a Newton step)
  std::vector<uint8_t> valid, valid_a;
  std::vector<Jac23> J;
  std::vector<Mat26> D;           // d uv / d T0 (left), row dependence included
  std::vector<Jac23> E;           // d uv / d w (the twist's rotation), row dependence included (rate estimated)
  std::vector<double> row;        // rolling shutter: Newton's row per point (warm start within a guess)
  std::vector<int> active, still;
  FrameTracker::Linearization lin;
};

struct FrameTracker::LevelPoints {
  int n = 0;
  std::vector<PatternHost> host;
  std::vector<Vec2> host_uv0;   // level-0 coordinates of the (merged) host pixel
  std::vector<Vec3> host_point; // point in the host camera at its row time
  std::vector<Block> blocks;
};

// One guess tracked through the levels.
struct FrameTracker::Attempt {
  bool ok = false;
  std::string failure;
  SE3d T_c_w;
  AffineBrightness affine;
  Vec6 twist = Vec6::Zero();  // the twist of the last level (TrackerOptions::twist_refresh_levels)
  std::array<double, 6> level_rmse;
  int iterations = 0;
  Attempt() { level_rmse.fill(std::nan("")); }
};

// [I, -[p]x]: d(exp(d) p) / d d at d = 0 (left perturbation, tangent (translation; rotation)).
inline Eigen::Matrix<double, 3, 6> dLeftAction(const Vec3& p) {
  Eigen::Matrix<double, 3, 6> J;
  J.leftCols<3>().setIdentity();
  J.rightCols<3>() = -SO3d::hat(p);
  return J;
}

// t_target / t_host when both exposures are known, else 1.
inline double exposureRatio(double host_ms, double target_ms) {
  return (host_ms > 0.0 && target_ms > 0.0) ? target_ms / host_ms : 1.0;
}

}  // namespace rsvio
