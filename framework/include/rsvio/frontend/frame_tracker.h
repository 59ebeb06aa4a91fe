// Direct frame tracking: coarse-to-fine alignment of a new frame against the newest keyframe's points
// (DSO's CoarseTracker, Engel et al. 2018, sec. 4.1; paper sec. IV-A, "frontend").
//
// Contract
// - State of the new frame: central pose T_c_w^0 (world -> camera at the image timestamp, row y0) and
//   affine brightness (a, b). Its rolling-shutter twist is NOT estimated here: it is an input (the
//   prior's or the previous frame's), and every point is projected with the rolling-shutter constraint
//   solved by Newton on the row as in geometry/rs_projection.h (own loop: only d uv / d T_c_w^0,
//   rows warm-started within a guess; tested against rs_projection.h), so the Jacobian w.r.t.
//   T_c_w^0 includes the row dependence.
//   Poses are perturbed on the LEFT, T <- exp(delta) T (rsvio/lie/lie.h).
// - Reference: the keyframe's pose, twist, affine brightness, pyramid and points (host pixel, inverse
//   depth along the camera's unit bearing, i.e. 1 / distance). Every point is fixed in the world at
//   its host row time. On pyramid level l the points are merged per level pixel (inverse depths
//   averaged, as DSO's makeCoarseDepthL0) and the pattern is used in level pixels.
// - Residual and weights: photometric_residual.h (8-pixel pattern, Huber, gradient weights), with W = I
//   (no pattern warp) and DSO's cutoff: a pattern pixel with |r| > cutoff counts with the energy of
//   |r| = cutoff and no derivative; when more than 60 % saturate the cutoff is doubled (up to 50 x).
// - Optimisation per level: Levenberg-Marquardt on (delta(6), a, b) from the coarsest level down
//   (DSO's trackNewestCoarse: lambda 0.01, x0.5 on success, x4 on failure, 10/20/50/50/50
//   iterations on levels 0..4), stop when the scaled increment is below 1e-3.
// - Guesses (the motion prior's predict(), best first): each is tracked through all levels; one is
//   abandoned at a level where its RMSE exceeds abort_factor x the best RMSE reached so far on that
//   level; the first whose level-0 RMSE is below retrack_factor x the last frame's stops the search
//   (DSO's setting_reTrackThreshold). The best (lowest level-0 RMSE) wins.
// - Tracking lost: the result says Lost with a reason when no guess leaves enough points in view,
//   when the winner's inlier ratio (share of pattern pixels with |r| <= cutoff) is below
//   min_inlier_ratio, its RMSE above max_rmse, its explained ratio below min_explained_ratio (unless it
//   is close to the last tracked frame's: TrackerOptions::explained_keep_fraction), or its
//   brightness change out of range. A lost result still carries the best pose found; callers must not
//   use it as a measurement.
// - Explained ratio: the share of the level-0 points in view whose pattern the pose explains, i.e.
//   sum_k r_k^2 < explained_residual^2 x sum_k (I_k - mean_k I_k)^2 over the 8 target intensities I_k
//   (by default the residual RMS is below half the pattern's own intensity spread: the affine-corrected
//   host pattern reproduces the target's local structure). On smooth texture a wrong pose can keep the
//   RMSE and the inlier ratio in range (the brightness fit flattens the prediction and the residuals
//   stay about as large as the target's own variation) but explains almost no point; occluded points
//   lower the ratio only in proportion to their share. Measured (simulator tiny_gs/tiny_rs: 6 keyframes
//   x 3 targets, guesses up to 0.3 m / 0.6 rad, 900 tracks; rendered scene of tracker_test.cpp with
//   noise sigma 0-6, 480 tracks): right poses 0.48 - 0.98, >= 0.35 with 45 % of the target image
//   replaced by other scene content; wrong poses (> 5 cm or 0.02 rad) <= 0.04 (simulator), <= 0.16
//   (rendered scene), <= 0.15 under that occlusion. min_explained_ratio = 0.25 lies between. (One
//   wrong pose reached 0.36 where the replaced 45 % showed the same scene from another viewpoint, a
//   second consistent alignment.) A plain RMSE relative to the intensity spread separated clean
//   images as well but not occluded ones (right poses up to 1.44, wrong from 0.92).
// - Determinism: points are processed in fixed blocks whose sums are added in block order, so the
//   result is identical for 1 and 2 threads (at most 2 are used).
#pragma once
#include <array>
#include <cmath>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "rsvio/core/types.h"
#include "rsvio/geometry/rs_projection.h"
#include "rsvio/lie/se3.h"
#include "rsvio/photometric/image_pyramid.h"
#include "rsvio/photometric/photometric_residual.h"
#include "rsvio/plugin/plugin.h"

namespace rsvio {

class CameraModel;
class BlockRunner;

struct TrackerOptions {
  ResidualOptions residual;
  int max_levels = 5;                               // pyramid levels used (coarsest = max_levels - 1)
  std::array<int, 6> max_iterations = {10, 20, 50, 50, 50, 50};  // per level (DSO)
  double cutoff_th = 20.0;                          // intensity; DSO setting_coarseCutoffTH
  double lambda_initial = 0.01;
  double converge_eps = 1e-3;                       // norm of the scaled increment
  double retrack_factor = 1.5;                      // accept a guess below this x the last RMSE
  double abort_factor = 1.5;                        // drop a guess above this x the best level RMSE
  // Tracking-lost tests on the winner.
  int min_points = 30;                              // points with a residual on level 0
  double min_inlier_ratio = 0.5;
  double max_rmse = 14.0;                           // intensity (sqrt of energy per pattern pixel)
  double min_explained_ratio = 0.25;                // share of the points in view explained (see above)
  double explained_residual = 0.5;                  // per point: residual RMS / its pattern's intensity spread
  // A winner below min_explained_ratio is kept (TrackResult::poorly_explained) when its ratio is at least
  // explained_keep_fraction x the last tracked frame's and at least min_explained_floor: a model that lacks
  // an effect (a rolling shutter tracked as a global one, exposure without affine brightness) explains
  // each frame a little less than the one before as it moves away from the keyframe, where a wrong pose
  // drops the ratio at once (docs/frontend.md, "Poorly explained frames"). 0: never kept.
  // A sustained failure is not kept: no frame is kept when max_poorly_explained of the last 10 tracked
  // frames were poorly explained (a run whose state broke at its start fades as gradually, but longer).
  double explained_keep_fraction = 0.4;
  double min_explained_floor = 0.08;
  int max_poorly_explained = 6;
  double max_abs_log_alpha = 1.5;                   // |log(exposure ratio exp(a_j - a_i))| (DSO)
  double max_abs_b = 200.0;                         // intensity
  // Which brightness parameters the tracker estimates (the back end sets these from the photometric
  // models: photometric.affine present -> both true).
  bool estimate_a = true;
  bool estimate_b = true;
  int threads = 1;                                  // 1 or 2; results are identical
  // Rolling shutter: a frame lost with its predicted twist is tracked again up to this many times, each
  // time with the twist's rotation re-estimated from the pose the last attempt reached (Odometry's
  // track(); the tracker itself holds the twist it is given).
  int twist_retries = 2;
  // Rolling shutter: a tracked frame is tracked again this many times from the pose it reached, with the
  // twist's rotation re-estimated as the rate through that pose (Tracking::track; skipped when the
  // rotation is measured, TrackingFrame::twist_measured). docs/rolling_shutter.md, "Twist refinement".
  int twist_refinements = 0;
  // Rolling shutter: within each guess's coarse-to-fine pass, the twist's rotation is set to
  // TrackingFrame::rotation_rate_of_pose(pose reached) before each solve of the levels below this number
  // (a level DSO repeats too), so they are solved with the rate through the pose found so far (0: the
  // twist stays fixed; 1: before level 0 only).
  int twist_refresh_levels = 0;
  // Rolling shutter: > 0 estimates the twist's rotation with the pose (its readout shear and stretch are
  // in the image), under a prior of this sigma [rad/s] about the given twist's; 0 holds the twist fixed.
  double rotation_rate_sigma = 0.3;

  static ParamTable paramTable();                   // keys track_* (see frontend_options.h)
  // Reads the track_* keys; `residual` is left for the caller (ResidualOptions::fromParams).
  static TrackerOptions fromParams(const Params& p);
};

// One point of the reference keyframe.
struct TrackingPoint {
  Vec2 uv = Vec2::Zero();   // host pixel, level 0 (integer for selected points)
  double idepth = 0.0;      // inverse distance along the unit bearing of uv
  double weight = 1.0;      // relative weight when points merge on coarse levels (e.g. depth information)
};

struct TrackingReference {
  int64_t frame_id = -1;
  int64_t t_ns = 0;
  SE3d T_c_w;                           // central pose
  Vec6 twist = Vec6::Zero();            // per second
  Vec3 w_dot = Vec3::Zero();            // the twist rotation's rate of change (RsFrame::w_dot), rad/s^2
  AffineBrightness affine;
  double exposure_ms = std::numeric_limits<double>::quiet_NaN();
  std::shared_ptr<const ImagePyramid> pyramid;
  std::vector<TrackingPoint> points;
};

// What the tracker needs to know about the new frame besides its image.
struct TrackingFrame {
  int64_t t_ns = 0;
  Vec6 twist = Vec6::Zero();            // predicted; held fixed, except its rotation with estimate_rotation_rate (then the prior's mean)
  bool twist_measured = false;          // its rotation is the gyroscope's: Tracking does not refine it
  // Estimate the twist's rotation (TrackerOptions::rotation_rate_sigma > 0): set by Tracking::track with
  // two frames of history and an unmeasured rotation; the monocular start's frames hold their twists.
  bool estimate_rotation_rate = false;
  Vec3 w_dot = Vec3::Zero();            // RsFrame::w_dot, kept fixed (the gyroscope's; zero without it)
  // TrackerOptions::twist_refresh_levels: the twist's rotation as a function of the frame's central
  // pose T_c_w (rad/s, camera frame); empty: the twist is held.
  std::function<Vec3(const SE3d&)> rotation_rate_of_pose;
  double exposure_ms = std::numeric_limits<double>::quiet_NaN();
  AffineBrightness affine_guess;        // usually the previous frame's
};

struct TrackResult {
  enum class Status { Ok, Lost };
  Status status = Status::Lost;
  std::string reason;                   // empty when Ok; one line otherwise
  SE3d T_c_w;                           // central pose of the new frame
  AffineBrightness affine;
  Vec6 twist = Vec6::Zero();            // the twist the result was tracked with (TrackingFrame::twist, refreshed, or rate estimated)
  bool rate_estimated = false;          // twist's rotation estimated with the pose (TrackingFrame::estimate_rotation_rate)
  double rmse = 0.0;                    // level 0, intensity units
  std::array<double, 6> level_rmse{};   // per level (NaN where not reached)
  double inlier_ratio = 0.0;            // level 0, |r| <= cutoff
  double explained_ratio = 0.0;         // level 0: share of the points in view explained (contract)
  bool poorly_explained = false;        // Ok although explained_ratio < min_explained_ratio (TrackerOptions)
  int num_points = 0;                   // points with a residual on level 0
  int guess_index = -1;                 // which guess won
  int guesses_tried = 0;
  int iterations = 0;                   // LM iterations over all levels and guesses
  // DSO's keyframe indicators: RMS pixel shift of the level-0 points with the full relative motion,
  // and with its translation only (rotation removed).
  double flow_rt_px = 0.0;
  double flow_t_px = 0.0;
  bool ok() const { return status == Status::Ok; }
};

class FrameTracker {
 public:
  FrameTracker(const TrackerOptions& options, const CameraModel& camera, const RowTiming& timing);
  // A new line delay (estimated online); takes effect with the next setReference().
  void setTiming(const RowTiming& timing) { timing_ = timing; }
  ~FrameTracker();
  FrameTracker(const FrameTracker&) = delete;
  FrameTracker& operator=(const FrameTracker&) = delete;

  // Builds the per-level point sets. Points outside the host image or with idepth <= 0 are skipped.
  void setReference(const TrackingReference& reference);
  bool hasReference() const { return static_cast<bool>(ref_.pyramid); }
  const TrackingReference& reference() const { return ref_; }
  int numReferencePoints(int level) const;

  // Tracks one frame from the guesses (best first; an empty list means "the keyframe's pose").
  // track() keeps no memory of its result: the caller accept()s the one result it keeps for a frame.
  TrackResult track(const ImagePyramid& frame, const TrackingFrame& info, const std::vector<SE3d>& guesses);
  // Commits the result kept for one frame (Ok; ignored otherwise): its RMSE per level (lastRmse(), the
  // early stop over guesses), firstRmse() and the explained-ratio memory that keeps poorly explained
  // frames (explained_keep_fraction, max_poorly_explained). Once per frame: retries and refinements
  // that were tried and dropped must not count as tracked frames.
  void accept(const TrackResult& result);

  // RMSE per level of the last accepted track (DSO's lastCoarseRMSE); NaN before the first.
  const std::array<double, 6>& lastRmse() const { return last_rmse_; }
  // Level-0 RMSE of the first accepted track since setReference() (DSO's firstCoarseRMSE: a frame
  // whose RMSE exceeds twice this calls for a keyframe); NaN until then.
  double firstRmse() const { return first_rmse_; }

  const TrackerOptions& options() const { return options_; }

  // Energy of the pose/affine pair on one level, for tests: rmse, inlier ratio, points in view and
  // explained.
  struct LevelEnergy {
    double energy = 0.0;
    int num_terms = 0;       // pattern pixels evaluated
    int num_saturated = 0;   // |r| > cutoff
    int num_points = 0;      // points in view
    int num_explained = 0;   // points in view whose pattern is explained (contract)
    double rmse() const { return num_terms > 0 ? std::sqrt(energy / num_terms) : std::nan(""); }
  };
  LevelEnergy levelEnergy(const ImagePyramid& frame, const TrackingFrame& info, int level, const SE3d& T_c_w,
                          const AffineBrightness& affine) const;

  // The reference points of one level projected into a frame with central pose T_c_w and twist (the
  // tracker's own rolling-shutter solve), with d uv / d T_c_w (left perturbation, row dependence
  // included). Level-0 pixels; X_w (optional) receives the points in the world; w_dot the frame's
  // RsFrame::w_dot; d_uv_d_w (optional, with d_uv_d_T) d uv / d (the twist's rotation), the Jacobian
  // the tracker estimates the rate with (TrackerOptions::rotation_rate_sigma; zero for a global
  // shutter). For tests and diagnostics.
  void projectReference(int level, const SE3d& T_c_w, const Vec6& twist, Eigen::Matrix2Xd* uv,
                        std::vector<uint8_t>* valid, std::vector<Eigen::Matrix<double, 2, 6>>* d_uv_d_T,
                        Eigen::Matrix3Xd* X_w = nullptr, const Vec3& w_dot = Vec3::Zero(),
                        std::vector<Eigen::Matrix<double, 2, 3>>* d_uv_d_w = nullptr) const;

 private:
  struct LevelPoints;
  struct Block;
  struct Linearization;
  struct Attempt;

  // rate: with linearize, also d uv / d w (the twist's rotation) and its blocks of the normal equations.
  void projectBlock(Block& B, const RsFrame& target, bool linearize, bool rate = false) const;
  void resetRows() const;
  // Whether this frame's twist rotation is estimated (TrackingFrame::estimate_rotation_rate, a rolling
  // shutter, TrackerOptions::rotation_rate_sigma > 0).
  bool estimatesRate(const TrackingFrame& info) const;
  // Whether a winner with this explained ratio (below min_explained_ratio) is kept: close enough to the
  // last tracked frame's (TrackerOptions::explained_keep_fraction, min_explained_floor).
  bool keptPoorlyExplained(double explained_ratio) const;
  void evaluate(const ImageLevel& img, int level, const RsFrame& target, const AffineBrightness& aff,
                double alpha_ratio, double cutoff, bool linearize, Linearization& out, bool rate = false) const;
  Attempt trackGuess(const ImagePyramid& frame, const TrackingFrame& info, const SE3d& guess,
                     const std::array<double, 6>& abort_rmse) const;

  TrackerOptions options_;
  const CameraModel& camera_;
  RowTiming timing_;
  TrackingReference ref_;
  std::vector<std::unique_ptr<LevelPoints>> levels_;
  std::array<double, 6> last_rmse_;
  double first_rmse_ = std::nan("");
  double last_explained_ = std::nan("");   // explained ratio of the last frame accepted (any reference)
  unsigned recent_poor_ = 0;               // bit i: the i-th last accepted frame was poorly explained
  std::unique_ptr<BlockRunner> runner_;
};

}  // namespace rsvio
