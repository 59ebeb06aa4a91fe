// Candidate (immature) points: inverse depth from an epipolar search in later frames, before the back
// end activates them into the optimisation (DSO's ImmaturePoint::traceOn, Engel et al. 2018, sec. 3.3).
//
// Contract
// - A candidate lives in its host keyframe: level-0 host pixel uv_h, unit bearing b, PatternHost, the
//   host gradient structure tensor sum g g^T over the pattern. Inverse depth rho = 1 / distance along b
//   (the parametrisation of point_observation.h), known as an interval [idepth_min, idepth_max];
//   initially [0, inf) (rho = 0: at infinity).
// - trace() searches each candidate in a target frame along its epipolar curve, i.e. the projection of
//   X(rho) = T_h(t_h)^-1 (b / rho) for rho in the interval, through the camera model (raw image,
//   distortion included: the "line" may be curved). Host row time t_h = t(v_h); the target pose is taken
//   at the row time of the candidate's last match (else of its host row) and the interval is computed
//   with the pose at the row of the new match (rolling shutter, eq. 6-7).
// - Search (DSO): samples every step_px along the curve (at most max_search_frac (w + h) px), pattern
//   energy with Huber weights and the affine transfer; best and second best (outside +-2 samples) give
//   the match quality second/best; then Gauss-Newton along the curve's tangent (<= 3 steps of <= 0.5 px).
// - Uncertainty (DSO's errorInPixel): e = 0.2 + 0.2 (a + b) / a px, a and b the host gradient energy
//   along and across the search direction, e <= 10 px. The new interval is the inverse depths of the
//   match +- e px along the curve (exact per camera: unproject, closest point on the host ray).
// - Statuses: Good (interval updated), Skipped (interval already below slack_interval_px in this
//   target), BadCondition (the search could not improve the interval by min_improvement), Outlier
//   (pattern energy above the outlier threshold; twice in a row -> OutOfBounds), OutOfBounds (the
//   search leaves the image or the scale changes too much; final, the back end drops the point).
// - Batches: three camera batch calls per trace() (end points, samples, match unprojections), whatever
//   the number of candidates; deterministic.
#pragma once
#include <Eigen/Core>
#include <limits>
#include <vector>

#include "rsvio/geometry/rs_projection.h"
#include "rsvio/interfaces/camera.h"
#include "rsvio/photometric/photometric_residual.h"
#include "rsvio/plugin/plugin.h"

namespace rsvio {

struct CandidateOptions {
  double step_px = 1.0;                 // discrete search step (DSO setting_trace_stepsize)
  double max_search_frac = 0.027;       // longest search, fraction of (w + h) (DSO setting_maxPixSearch)
  int gn_iterations = 3;                // DSO setting_trace_GNIterations
  double gn_threshold_px = 0.1;         // stop GN below this step
  double slack_interval_px = 1.5;       // interval already this short: skip (DSO setting_trace_slackInterval)
  double min_improvement = 2.0;         // DSO setting_trace_minImprovementFactor
  double outlier_slack = 1.2;           // energy threshold factor (DSO setting_trace_extraSlackOnTH)
  int second_best_radius = 2;           // samples around the best excluded from the second best
  double min_quality = 3.0;             // activation: second best / best energy (DSO setting_minTraceQuality)
  double max_activation_interval_px = 8.0;  // activation: last interval shorter than this

  static ParamTable paramTable();       // keys trace_* (see frontend_options.h)
  static CandidateOptions fromParams(const Params& p);
};

enum class CandidateStatus { Uninitialized, Good, Skipped, BadCondition, Outlier, OutOfBounds };
const char* candidateStatusName(CandidateStatus s);

struct CandidatePoint {
  Vec2 uv = Vec2::Zero();            // host pixel, level 0
  Vec3 bearing = Vec3::UnitZ();      // unit bearing
  Jac32 d_bearing_d_uv = Jac32::Zero();
  PatternHost pattern;
  Eigen::Matrix2d grad_h = Eigen::Matrix2d::Zero();  // sum over the pattern of g g^T (host)
  double energy_th = 0.0;            // outlier energy threshold
  double idepth_min = 0.0;
  double idepth_max = std::numeric_limits<double>::infinity();
  double quality = 10000.0;          // second best / best energy of the last long search
  CandidateStatus status = CandidateStatus::Uninitialized;
  Vec2 last_uv = Vec2(-1, -1);       // match in the last traced target (level 0)
  double last_interval_px = 0.0;     // length of the interval in the last traced target
  double last_row_time_s = 0.0;      // row time of the last match
  int num_good = 0;                  // traces that ended Good

  bool hasDepth() const { return std::isfinite(idepth_max) && idepth_max > 0.0; }
  double idepth() const { return 0.5 * (idepth_min + idepth_max); }
  double idepthHalfWidth() const { return 0.5 * (idepth_max - idepth_min); }
  // DSO's activation test: traced, interval short in pixels, match unambiguous, depth positive.
  bool readyForActivation(const CandidateOptions& o) const;
};

// A frame as the tracer needs it: central pose and twist, brightness, exposure.
struct CandidateFrame {
  RsFrame pose;
  AffineBrightness affine;
  double exposure_ms = std::numeric_limits<double>::quiet_NaN();
};

struct TraceStats {
  int good = 0, skipped = 0, bad_condition = 0, outlier = 0, out_of_bounds = 0, already_out = 0;
};

class CandidateTracer {
 public:
  CandidateTracer(const CandidateOptions& options, const ResidualOptions& residual, const CameraModel& camera,
                  const RowTiming& timing);
  // A new line delay (estimated online): later traces use it.
  void setTiming(const RowTiming& timing) { timing_ = timing; }

  // Candidates at pixels of a keyframe (its level-0 image). Pixels whose pattern leaves the image or
  // that the camera cannot unproject are dropped.
  std::vector<CandidatePoint> create(const ImageLevel& host_level0, const std::vector<Vec2>& pixels) const;

  // Traces every candidate of one host into one target frame (its level-0 image).
  TraceStats trace(std::vector<CandidatePoint>& points, const CandidateFrame& host, const CandidateFrame& target,
                   const ImageLevel& target_level0) const;

  const CandidateOptions& options() const { return options_; }

 private:
  CandidateOptions options_;
  ResidualOptions residual_;
  const CameraModel& camera_;
  RowTiming timing_;
};

}  // namespace rsvio
