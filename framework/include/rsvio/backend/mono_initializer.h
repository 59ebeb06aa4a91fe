// Monocular initialisation for runs without an IMU: the relative pose of a later frame to a reference
// frame, with enough parallax that the depths of the reference's candidate points can be found by the
// epipolar search, and a scale (median depth 1).
//
// DSO (Engel et al. 2018, sec. 3.4 "Initialization") optimises pose and inverse depths jointly from a
// constant-depth start, coarse to fine, with an inverse-depth regulariser. rsvio takes the classic
// two-view route for that first guess, then hands it to the same photometric machinery DSO ends with
// (epipolar search of the candidates, then the windowed bundle adjustment), which is robust to the
// fast rotations of handheld motion that a constant-depth start struggles with:
// - corners (Shi-Tomasi) of the reference are tracked frame to frame with pyramidal Lucas-Kanade on
//   the frames' image pyramids (9x9 window, coarse to fine) and a forward-backward check (1 px); when
//   fewer than a third survive, the current frame becomes the new reference;
// - from init_min_frames on, once the median corner flow exceeds init_min_flow_px of the image
//   diagonal: essential matrix by the normalised 8-point algorithm in RANSAC (Sampson distance, on the
//   unit-focal image plane of the camera's own unprojection, so any camera model works), the pose of
//   the four decompositions with most points in front of both cameras, and the checks: inlier ratio
//   >= init_min_inlier_ratio, median triangulation angle >= init_min_parallax_deg, 90 % of the
//   inliers in front.
// - The result T_cur_ref (camera_cur from camera_ref) is scaled so that the median depth of the
//   triangulated inlier corners in the reference is 1 (DSO also normalises the initial scene to mean
//   inverse depth 1).
// - Rolling shutter (a RowTiming with a line delay): the corners of each image were read at their own
//   rows' times. The fit's motion is taken as a constant twist between the two timestamps,
//   xi = log(T_cur_ref) / dt (per second, left form of shutter.h: P(tau) = exp(xi tau) P(0)); every
//   bearing is moved to its image's central pose through its triangulated depth (its rotation alone
//   where the rays do not meet), and the essential matrix is fitted again from the inliers, for
//   init_rolling_shutter_iterations rounds (default 0: off). With init_keyframe_twist the twist is
//   handed on (xi()) as the start of keyframe 0's twist (default off). On exact correspondences the
//   rounds remove the readout's bias (tests/framework/backend/two_view_test.cpp), but on the demo
//   sequences the bias is below the corner noise and the runs did not improve: docs/rolling_shutter.md.
// - Rolling shutter, each image's own rotation rate (init_rotation_rates, default on): over a
//   0.3-0.5 s start the rotation rate of handheld motion can change by more than its mean, so one
//   constant twist for both images cannot remove the readout's shear, and that shear (10-12 px over
//   the image at 0.9 rad/s and 30 ms) can exceed the translation's parallax: the essential matrix then
//   explains the shear as translation. Each image's rate is measured from its neighbour frames
//   instead (fitRotationRate: the corner tracks of two consecutive frames, 50 ms apart, where the
//   rotation dominates the flow; two consecutive pairs give the rate's trend, extrapolated to the
//   image's timestamp; from the 3rd frame after the reference on), every bearing is rotated to its
//   image's central pose with that rate (exp(-[w] tau), no depth needed), and the essential matrix is
//   fitted on those bearings. The rounds above are then not run (they would put one average twist
//   back). xiRef() and xiCur() hand the images' twists on: the measured rates and the fit's average
//   translation velocity. Figures: docs/rolling_shutter.md, "The start". With a rate source
//   (setRateSource: the gyroscope in a visual-inertial run, imu.init_rates_from_gyro) the rates are
//   the source's at each image's timestamp, from the first frame after the reference on.
// - Corner guesses (setTrackGuessSource: the gyroscope in a visual-inertial run,
//   imu.init_track_guess_from_gyro, off by default): each corner's Lucas-Kanade search starts at its
//   bearing rotated by the camera's rotation since the previous frame, plus the flow that the rotation
//   left unexplained in the corner's previous step (the translation's, taken as constant over a frame
//   interval; each row's own time is not used: the guess only has to fall in the search's basin),
//   instead of at its old position. At seq02's 73 deg/s a corner moves 30-70 px per frame over
//   repetitive texture, and the zero-motion guess kept about a quarter of the corners per frame
//   (docs/vio.md, "Gyroscope-rotated corner guesses").
// - Brightness of the tracked corners (lastSteps()): each frame-to-frame step keeps, per surviving
//   track, the mean working-image intensity of the 3x3 pixels around the corner in the previous and
//   in the current frame (level 0, bilinear). The run writes them to its diagnostics log (TrackRow),
//   so that probe.exposure sees how brightness changed over the first frames even when the run fails
//   before its first window (an exposure change the model lacks can make it fail there). The step
//   out of a reference frame is not kept: there the corners sit where the detector put them (whole
//   pixels, on the corner's apex), and their 3x3 means differed from those of the tracked positions by
//   up to 2 % on clean 640x512 sequences (0.1-0.7 % for later steps).
// - Brightness from the reference to the current frame (logGainCurRef()): the median ratio of the
//   tracks' 3x3 means in the current frame to those in the reference. A run that estimates affine
//   brightness starts the second keyframe (and the candidates' trace into it) with it: the trace's
//   search does not model brightness beyond its affine guess, and over a 0.5 s start the exposure can
//   change by a third (docs/diagnose.md, "Exposure from the start's corners").
#pragma once
#include <cstdint>
#include <functional>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "rsvio/backend/backend_options.h"
#include "rsvio/geometry/rs_projection.h"
#include "rsvio/lie/se3.h"
#include "rsvio/photometric/image_pyramid.h"

namespace rsvio {

class CameraModel;

struct TwoViewOptions {
  int rolling_shutter_iterations = 3;  // rounds of moving the bearings to the central poses (the odometry
                                       // passes backend.init_rolling_shutter_iterations, default 0)
  // Rolling shutter: each image's rotation rate (rad/s, the rotation part of a twist, left form), used
  // to rotate its bearings to its central pose before the fit; then the rounds above are not run.
  bool use_rates = false;
  Eigen::Vector3d w_ref = Eigen::Vector3d::Zero(), w_cur = Eigen::Vector3d::Zero();
};

struct TwoViewResult {
  bool found = false;       // a pose with depths (the caller applies the acceptance checks)
  SE3d T_cur_ref;           // camera_cur from camera_ref, median inlier depth in the reference 1
  Vec6 xi = Vec6::Zero();   // the constant twist per second between the timestamps (0 for a global shutter)
  Vec6 xi_ref = Vec6::Zero(), xi_cur = Vec6::Zero();  // with use_rates: each image's twist (its rate,
                                                      // the fit's average translation velocity)
  int correspondences = 0;  // with valid bearings in both images
  int inliers = 0, front = 0, num_depths = 0;
  double inlier_ratio = 0.0, parallax_deg = 0.0;
  std::string status;       // one line
};

// The geometric half of MonoInitializer, on matched pixels (ref_px[i] <-> cur_px[i], working image):
// the 8-point essential matrix in RANSAC, the rolling-shutter rounds above when timing has a line
// delay, and the pose. dt_s: timestamp of cur minus that of ref. Deterministic for a given seed.
TwoViewResult solveTwoView(const std::vector<Vec2>& ref_px, const std::vector<Vec2>& cur_px, const CameraModel& camera,
                           const RowTiming& timing, double dt_s, uint64_t seed, const TwoViewOptions& options);

// The rotation rate w (rad/s; left form, camera coordinates at time t are exp([w] t) times those at
// 0, the rotation part of a twist) that carries the bearings `a` of one image to the bearings `b` of a
// later image of the same static points, translation neglected (right over one frame interval, where
// the rotation dominates the flow): b_k = exp([w] dt_k) a_k with dt_k = dt + tau_b[k] - tau_a[k], each
// bearing at its own row's time (tau, relative to its image's timestamp; dt: timestamp of b minus that
// of a). Gauss-Newton from 0 on the bearings' differences, 3 rounds, then once more without the
// bearings whose residual exceeds 3 times the median (KLT slips). Returns false with fewer than 8
// bearings or a singular system.
bool fitRotationRate(const std::vector<Eigen::Vector3d>& a, const std::vector<double>& tau_a,
                     const std::vector<Eigen::Vector3d>& b, const std::vector<double>& tau_b, double dt,
                     Eigen::Vector3d* w);

class MonoInitializer {
 public:
  // timing: when each row was read (global: every row at the timestamp).
  MonoInitializer(const BackendOptions& options, const CameraModel& camera, const RowTiming& timing);

  // pyramid: the frame's image pyramid (working image); t_ns its timestamp. Returns true once a pose
  // is found; then T_cur_ref(), xi(), referenceIndex() describe it. The first call (and every reset)
  // sets the reference. Deterministic (RANSAC samples from a fixed seed).
  bool addFrame(std::shared_ptr<const ImagePyramid> pyramid, int64_t frame_index, int64_t t_ns);

  bool hasReference() const { return ref_index_ >= 0; }
  int64_t referenceIndex() const { return ref_index_; }
  int framesSinceReference() const { return frames_since_ref_; }
  const SE3d& T_cur_ref() const { return T_cur_ref_; }
  const Vec6& xi() const { return xi_; }  // twist per second of both frames (rolling shutter), else 0
  // With init_rotation_rates on a rolling shutter: each image's own twist (else both xi()), and
  // whether the start used them (from the 3rd frame after the reference on).
  bool ratesUsed() const { return rates_used_; }
  const Vec6& xiRef() const { return xi_ref_; }
  const Vec6& xiCur() const { return xi_cur_; }
  double medianParallaxDeg() const { return parallax_deg_; }
  // Rolling shutter with init_rotation_rates: where the source gives an image's rotation rate (the
  // rotation part of a twist, left form, rad/s, at the image's camera timestamp t_ns; the gyroscope
  // in a visual-inertial run), it replaces the rate fitted from the corner tracks, and it is used from
  // the first frame after the reference on. A source that returns false for either image leaves the
  // fitted rates (or none) for that attempt.
  using RateSource = std::function<bool(int64_t t_ns, Eigen::Vector3d* w)>;
  void setRateSource(RateSource source) { rate_source_ = std::move(source); }
  // The camera's rotation from t0 to t1 (camera timestamps, ns): camera coordinates of a static point
  // at t1 are R_1_0 times those at t0, translation neglected. Returns false where it is not known (the
  // corner then starts where it was).
  using RotationSource = std::function<bool(int64_t t0_ns, int64_t t1_ns, SO3d* R_1_0)>;
  void setTrackGuessSource(RotationSource source) { guess_source_ = std::move(source); }
  const std::string& status() const { return status_; }  // one line: what the last attempt found
  int numTracks() const { return static_cast<int>(cur_pts_.size()); }
  // The last addFrame's step: per track kept, its pixel in the current frame (working image) and the
  // 3x3 mean intensity there and at its position in the previous frame. Empty after a first frame, for
  // the step out of a reference frame and where no track was kept; lastStepFrom() is the previous
  // frame's index (-1 then).
  struct CornerStep {
    Vec2 px = Vec2::Zero();
    float intensity_prev = 0.f, intensity = 0.f;
  };
  const std::vector<CornerStep>& lastSteps() const { return steps_; }
  // log(median over the tracks of intensity in the current frame / intensity in the reference), 3x3
  // means (tracks with a reference intensity of at least 8 grey levels); 0 with fewer than 20 such
  // tracks. Lucas-Kanade assumes constant brightness, so corners drift a little along their gradients
  // under a gain and the ratio shows part of the change (3.7 % of 5 % in
  // tests/framework/backend/corner_guess_test.cpp); the bundle adjustment estimates the rest.
  double logGainCurRef() const;
  int64_t lastStepFrom() const { return step_from_; }

 private:
  void reset(int64_t frame_index, int64_t t_ns);
  bool tryInitialise();
  // Rotation rate of the image at history index `at`, from the frame pairs (i0, i0 + 1) and (i0 + 1,
  // i0 + 2), linearly extrapolated in time to that image's timestamp.
  bool rateAt(int i0, int at, Eigen::Vector3d* w) const;

  BackendOptions options_;
  const CameraModel& camera_;
  RowTiming timing_;
  int64_t ref_index_ = -1, ref_t_ns_ = 0, cur_t_ns_ = 0;
  int frames_since_ref_ = 0;
  int initial_tracks_ = 0;
  std::shared_ptr<const ImagePyramid> prev_;
  std::vector<cv::Point2f> ref_pts_, cur_pts_;
  std::vector<float> ref_intensity_;  // each track's 3x3 mean in the reference (NaN near the border)
  // With a rotation source: each track's flow in its last step that the rotation did not explain.
  std::vector<Vec2> unexplained_flow_;
  // Every frame's positions of the surviving tracks since the reference (hist_pts_[0] = ref_pts_,
  // back() = cur_pts_) and their timestamps, for the rotation rates.
  std::vector<std::vector<cv::Point2f>> hist_pts_;
  std::vector<int64_t> hist_t_ns_;
  std::vector<CornerStep> steps_;
  int64_t prev_index_ = -1, step_from_ = -1;
  RateSource rate_source_;
  RotationSource guess_source_;
  SE3d T_cur_ref_;
  Vec6 xi_ = Vec6::Zero(), xi_ref_ = Vec6::Zero(), xi_cur_ = Vec6::Zero();
  double parallax_deg_ = 0.0;
  bool rates_used_ = false;
  std::string status_;
};

}  // namespace rsvio
