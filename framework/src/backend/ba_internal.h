// Private state of BundleAdjuster shared by ba_linearize.cpp, ba_accumulate.cpp and ba_solve.cpp.
#pragma once
#include <Eigen/Core>
#include <memory>
#include <vector>

#include "rsvio/backend/bundle_adjustment.h"
#include "rsvio/frontend/block_runner.h"

namespace rsvio {
namespace ba {

// Point chunks of the deterministic sums: a fixed count, so results do not depend on the threads.
constexpr int kPointChunks = 16;

using Mat66 = Eigen::Matrix<double, 6, 6>;
using Vec6d = Eigen::Matrix<double, 6, 1>;
// d uv / d (host pose 6, host twist 6, target pose 6, target twist 6, idepth 1). A global-shutter
// linearisation fills the target pose and the inverse depth only (accumulateChunkGlobal).
using GeoJac = Eigen::Matrix<double, 2, 25>;
constexpr int kColHostPose = 0, kColHostTwist = 6, kColTargetPose = 12, kColTargetTwist = 18, kColIdepth = 24;

// One observation at one linearisation. The pattern's normal equations are kept factored in the six
// "virtual residual coordinates" (u, v, a_h, b_h, a_t, b_t): with the 8x6 matrix K = [G | A] (G the
// pattern gradients, A the affine Jacobians), M = K^T W K and g = K^T W r; the state Jacobian of those
// coordinates is GeoJac for (u, v) and selectors for the affine ones (DSO's factorisation, 2x2 + 2x4
// + 4x4 instead of 8 rows).
struct ObsLin {
  ObsState state = ObsState::kOob;
  float energy = 0.f;
  GeoJac Jg;
  Eigen::Vector2d Jl = Eigen::Vector2d::Zero();  // d uv / d line delay (filled when it is estimated)
  Mat66 M;
  Vec6d g;
  float u = 0.f, v = 0.f, grad_u = 0.f, grad_v = 0.f, mean_r = 0.f, mean_w = 0.f;
};

// All observations of one host into one target: evaluated with one batch projection.
struct PairWork {
  Keyframe* host = nullptr;
  Keyframe* target = nullptr;
  std::vector<int> obs;  // indices into Impl::obs_refs
  // scratch, reused
  Eigen::Matrix3Xd bearing;
  Eigen::VectorXd v_h, idepth;
  std::vector<RsHostProjection> proj;
  std::vector<RsHostPoint> host_pts;  // rolling shutter: the observations' Impl::host_points, gathered
};

struct ObsRef {
  int point = 0;  // index into Impl::points
  int obs = 0;    // index into the point's obs
};

struct Linearization {
  std::vector<ObsLin> obs;              // per ObsRef
  std::vector<double> Hpp, bp;          // per point (undamped)
  std::vector<double> hpl;              // per point: d^2 E / d rho d line_delay (when it is estimated)
  std::vector<int> blk_begin, blk_count;  // per point: involved blocks in the arena
  std::vector<int> blk_ids;             // window indices (host first)
  std::vector<double> hpc;              // kfDim values per arena entry: d^2 E / d rho d x_block
  // Per pair (h * nk + t), Adj(T_t T_h^-1) of the evaluated (central) poses, with which
  // d uv / d host pose = -d uv / d target pose * Adj (left perturbations of T_c_w, lie.h), for a
  // global and a rolling shutter alike (ba_accumulate.cpp, accumulateChunkGlobal and
  // accumulateChunkRolling).
  std::vector<Eigen::Matrix<double, 6, 6>> pair_adj;
  Eigen::MatrixXd Hcc;                  // cameras: photometric + priors + terms, undamped, unmasked
  Eigen::VectorXd bc;
  double energy_photo = 0.0;            // all observations (kOob/kOutlier at the outlier energy)
  double energy_photo_in = 0.0;         // kIn observations only
  double energy_other = 0.0;            // priors and terms
  int num_in = 0, num_oob = 0, num_outlier = 0;
  double total() const { return energy_photo + energy_other; }
};

struct ChunkSums {
  Eigen::MatrixXd H;
  Eigen::VectorXd b;
  // The line delay's row (when it is estimated): its coupling to the photometric dimensions, its own
  // entry and its gradient.
  Eigen::VectorXd Hl;
  double Hll = 0.0, bl = 0.0;
  // Global shutter (accumulateChunkGlobal): per host-target pair, the normal equations over
  // (target pose 6, host affine 2, target affine 2), mapped to the host pose with the pair's adjoint
  // once per chunk; pair_used marks the pairs this chunk touched.
  std::vector<Eigen::Matrix<double, 10, 10>> pair_H;
  std::vector<Eigen::Matrix<double, 10, 1>> pair_b;
  std::vector<uint8_t> pair_used;
  // Rolling shutter (accumulateChunkRolling): per pair, the upper triangles of the normal equations
  // over (target pose 6, host twist 6, target twist 6, line delay 1, host affine 2, target affine 2);
  // added over the chunks and mapped to the window's blocks by addRollingPairs (H, b, Hl stay unused).
  std::vector<Eigen::Matrix<double, 23, 23>> pair_Hr;
  std::vector<Eigen::Matrix<double, 23, 1>> pair_br;
  double energy = 0.0, energy_in = 0.0;
  int num_in = 0, num_oob = 0, num_outlier = 0;
};

}  // namespace ba

struct BundleAdjuster::Impl {
  using PairWork = ba::PairWork;
  using ObsRef = ba::ObsRef;
  using Linearization = ba::Linearization;
  using ChunkSums = ba::ChunkSums;
  std::unique_ptr<BlockRunner> runner;
  // Structure (rebuilt by buildStructure when the window changed).
  KeyframeList* window = nullptr;
  std::vector<ActivePoint*> points;
  std::vector<ObsRef> obs_refs;
  std::vector<int> point_obs_begin;     // per point, into obs_refs (its obs are contiguous)
  std::vector<PairWork> pairs;
  std::vector<uint8_t> fixed;           // per camera dimension
  int nc = 0;                           // camera dimensions: all keyframe and global states
  int nkd = 0;                          // photometric dimensions (the leading nkd of nc), coupled to points
  int gl = -1;                          // the line delay's dimension in nc when it is estimated, else -1
  RowTiming timing;                     // the row timing of this linearisation (line delay from the globals)
  // Linearisations: current (accepted) and trial.
  Linearization cur, trial;
  std::vector<ChunkSums> chunks;
  // Rolling shutter: each point's target-independent host part (rsHostPoint), computed once per
  // linearisation and shared by all the point's targets.
  std::vector<RsHostPoint> host_points;
  Eigen::MatrixXd probe_H;              // scratch of ba::cameraTermsEnergy
  Eigen::VectorXd probe_b;
  const MarginalizationPrior* prior = nullptr;
  GlobalStates* globals = nullptr;      // visual-inertial: updated with the keyframes
};

namespace ba {

// The linearisation's steps (ba_linearize.cpp, ba_accumulate.cpp), called by the solver (ba_solve.cpp).
void buildStructure(BundleAdjuster::Impl& m, KeyframeList& window, const BundleAdjustmentConfig& cfg,
                    const std::vector<ActivePoint*>* only);
// points_only: each point's H_pp, b_p, the observations and the energies, no camera blocks (L.Hcc,
// L.bc, L.hpc are left as they were: optimizeDepths reads none of them).
void linearizePhotometric(BundleAdjuster::Impl& m, Linearization& L, const BundleAdjustmentConfig& cfg,
                          const CameraModel& camera, const RowTiming& timing, bool points_only = false);
void addCameraTerms(BundleAdjuster::Impl& m, Linearization& L, const BundleAdjustmentConfig& cfg,
                    const std::vector<const WindowTerm*>& terms);
// linearizePhotometric in two halves: the residuals, weights and Jacobians of every observation
// (evaluatePhotometric), then the per-point and camera blocks from them (accumulatePhotometric).
void evaluatePhotometric(BundleAdjuster::Impl& m, Linearization& L, const BundleAdjustmentConfig& cfg,
                         const CameraModel& camera, const RowTiming& timing);
void accumulatePhotometric(BundleAdjuster::Impl& m, Linearization& L, const BundleAdjustmentConfig& cfg,
                           bool points_only);
// The energies alone, bit-identical to L.energy_photo and L.energy_other of the full linearisation: a
// trial step is judged on them, and only an accepted one is accumulated.
double photometricEnergy(const BundleAdjuster::Impl& m, const Linearization& L);
double cameraTermsEnergy(BundleAdjuster::Impl& m, const BundleAdjustmentConfig& cfg,
                         const std::vector<const WindowTerm*>& terms);
double keyframePriors(const Keyframe& kf, const BundleAdjustmentConfig& cfg, Eigen::Ref<Eigen::MatrixXd> H,
                      Eigen::Ref<Eigen::VectorXd> b);

}  // namespace ba
}  // namespace rsvio
