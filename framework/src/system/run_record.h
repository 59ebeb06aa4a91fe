// The run record of rsvio::Odometry: everything its outputs and diagnostics are written from
// (trajectory.tum, keyframes.tum, points.ply, states.csv, diagnostics.bin, report.json's stage times
// and warnings; conventions.md "Outputs").
//
// Owns
// - one FrameRecord per input frame in arrival order (untracked ones too), with the keyframe it was
//   tracked against and its pose relative to it;
// - one KeyframeRecord per keyframe of the run, by kf_id: the state it was last recorded with (for a
//   marginalised keyframe its final one);
// - the map points that left the window (those not yet taken out), the diagnostics log (one row per inlier observation when it
//   leaves the window, io/diagnostics_log.h; only those made since the last takeObservations() when a
//   run loop streams them out; the monocular start's corner steps as track rows), the stage times and
//   the run's warnings.
//
// Invariants
// - Frame indices are unique (sequence positions). Records are only appended, except that a frame's
//   record is refined when it becomes a keyframe or is tracked after the monocular start, and a
//   keyframe's record whenever its keyframe is optimised again; a restart (restart()) makes every frame
//   so far untracked and drops what the discarded attempt made (keyframe ids start again at 0 after it).
// - It sees the window only through what it is given: it is the window's WindowSink (what leaves
//   arrives in the order it leaves) and the outputs take the live window, whose keyframes and points
//   are reported with their current state in place of their records.
// - A global-shutter keyframe's recorded twist is its observed twist (central difference of the
//   neighbouring frames' poses) once the next frame is tracked; a rolling shutter's is its state's.
#pragma once
#include <cstdint>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "keyframe_window.h"
#include "rsvio/backend/mono_initializer.h"
#include "rsvio/interfaces/camera.h"
#include "rsvio/io/diagnostics_log.h"
#include "rsvio/io/states.h"
#include "rsvio/io/trajectory.h"
#include "rsvio/lie/rxso3.h"
#include "rsvio/system/odometry.h"
#include "stage_times.h"

namespace rsvio {

// One input frame as the estimator remembers it.
struct FrameRecord {
  int64_t index = 0;
  int64_t t_ns = 0;
  bool tracked = false;
  bool keyframe = false;
  int64_t ref_kf_id = -1;     // the keyframe it was tracked against (itself for a keyframe)
  SE3d T_f_ref;               // camera of this frame from the camera of the reference keyframe
  SE3d T_c_w;                 // as estimated when tracked (keyframes: updated by their optimisation)
  AffineBrightness affine;
  double exposure_ms = std::numeric_limits<double>::quiet_NaN();
};

// A keyframe's latest (for marginalised ones: final) state.
struct KeyframeRecord {
  int64_t kf_id = 0;
  int64_t frame_index = 0;
  int64_t t_ns = 0;
  KeyframeState state;
  double time_offset_s = 0.0;  // the camera-IMU time offset when the record was made (a global state)
  double line_delay_s = 0.0;   // the line delay then (rolling shutter; it may be estimated online)
  double scale = 0.0;          // the metric scale then (metres per W_f unit; 0 before the VI initialisation)
};

class RunRecord : public WindowSink {
 public:
  // camera and timing must outlive the record; calibration: the diagnostics log's image size.
  RunRecord(const CameraModel& camera, const RowTiming& timing, bool rolling, bool estimate_affine,
            const CameraCalibration& calibration);

  // Frames.
  void addFrame(const FrameRecord& f) { frames_.push_back(f); }
  FrameRecord* frame(int64_t index);  // the record of that frame, or nullptr
  const std::vector<FrameRecord>& frames() const { return frames_; }

  // The global states a keyframe's record also keeps (the time offset); without them, the
  // calibration's offset.
  void setGlobals(const GlobalStates* g) { globals_ = g; }
  // The scale became metric (visual-inertial initialisation at t_ns, the newest keyframe's time):
  // records from now on carry it, and the outputs are mapped to W_m (see the outputs below).
  void setMetric(int64_t t_ns) {
    metric_ = true;
    settled_t_ns_ = t_ns + static_cast<int64_t>(kScaleSettleS * 1e9);
  }
  // The scale of the first second after the initialisation is not used for the outputs: the window's
  // IMU factors are still refining it (tiny sequences: 6 % within 0.3 s; docs/vio.md "Outputs").
  static constexpr double kScaleSettleS = 1.0;

  // Keyframes: the current state of a keyframe (its twist: see the invariants).
  void recordKeyframe(const Keyframe& kf);
  // The observed twist is computed (and cached in kf once both neighbours are tracked), then recorded.
  void recordFinal(Keyframe& kf);
  long numKeyframes() const { return static_cast<long>(keyframes_.size()); }
  const std::map<int64_t, KeyframeRecord>& keyframeRecords() const { return keyframes_; }

  // WindowSink: what leaves the window.
  void observationLeaves(const ActivePoint& p, const ActiveObservation& o) override;
  void pointLeaves(const ActivePoint& p) override;
  void keyframeLeaves(Keyframe& kf) override { recordFinal(kf); }

  StageTimes& stages() { return stages_; }
  const StageTimes& stages() const { return stages_; }
  void addWarning(const std::string& w) { warnings_.push_back(w); }
  const std::vector<std::string>& warnings() const { return warnings_; }
  const DiagnosticsLog& diagnostics() const { return diag_; }
  // Moves the observation rows out (appended to *rows); the log keeps its header fields, IMU and track rows.
  void takeObservations(std::vector<ObservationRow>* rows);
  // The monocular start's corner step into frame `index` (t_ns) from frame `from` (TrackRow).
  void addTrackRows(int64_t index, int64_t t_ns, int64_t from, const std::vector<MonoInitializer::CornerStep>& steps);
  // A photometric model estimated online (PhotometricModel::estimatesOnline): every observation row
  // is also kept here until the back end hands them over (Odometry::Impl::refinePhotometric).
  void keepRowsForPhotometric(bool on) { keep_photometric_ = on; }
  std::vector<ObservationRow>& photometricRows() { return photometric_rows_; }
  // Moves the map points that left the window out (appended to *points), as points() maps them with
  // the records there are when they are taken (points taken before the initialisation stay in W_f;
  // those of a keyframe that left in the settling second take the current scale when no settled
  // record exists yet).
  void takePoints(std::vector<MapPoint>* points);
  // Provisional (a start that may still be restarted, Odometry::Impl::restart): takeObservations and
  // takePoints give nothing, so what a restart discards was never written out; the observation rows
  // and points stay here until it is set false.
  void setProvisional(bool on) { provisional_ = on; }
  bool provisional() const { return provisional_; }
  // A restart of the start (before the visual-inertial initialisation only): every frame so far becomes
  // untracked (no keyframe, no reference), and the keyframe records, map points, observation rows and
  // rows kept for photometric models are dropped. Track rows, stage times and warnings stay.
  void restart();

  // Outputs, with the keyframes and points still in `window` at their current state.
  // Trajectories are camera poses in W_f. With T_wm_wf given (visual-inertial, after the
  // initialisation), it receives per pose the scale-gravity transform that maps it to W_m: the current
  // gravity rotation with the scale its keyframe (a frame's: its reference keyframe's) was last recorded
  // with, so a keyframe that left the window keeps the metric scale it had then (the non-metric map's
  // scale drifts and the scale follows it; the final scale would carry today's back over the run).
  // Window keyframes take the current scale. Keyframes that left before the scale settled
  // (kScaleSettleS after the initialisation, and all those before it) take the scale of the first
  // keyframe recorded after that (the current one when there is none). The rotation is the current
  // one for all: it changes little, and per-record rotations would put steps into the trajectory's
  // rotation rates (probe.time_offset reads them).
  io::Trajectory frameTrajectory(const KeyframeList& window, std::vector<RxSO3d>* T_wm_wf = nullptr) const;
  io::Trajectory keyframeTrajectory(const KeyframeList& window, std::vector<RxSO3d>* T_wm_wf = nullptr) const;
  // Map points: in W_f for visual odometry; visual-inertial, in W_m with their host keyframe's
  // transform as above (window points: the current one).
  std::vector<MapPoint> points(const KeyframeList& window) const;
  std::vector<StateRow> states(const KeyframeList& window) const;

 private:
  // Twist of a keyframe seen from its neighbouring tracked frames (global shutter), per second.
  Vec6 observedTwist(Keyframe& kf) const;

  const CameraModel& camera_;
  const RowTiming& timing_;
  bool rolling_ = false;
  bool estimate_affine_ = false;
  double time_offset_s_ = 0.0;                   // the calibration's (assumed) offset
  const GlobalStates* globals_ = nullptr;
  double timeOffset() const { return globals_ ? globals_->state.time_offset_s : time_offset_s_; }
  bool metric_ = false;
  // StateRow::scale: 1 for visual odometry, 0 before the VI initialisation, then the estimate.
  double scaleNow() const { return !globals_ ? 1.0 : (metric_ ? globals_->state.T_wm_wf.scale() : 0.0); }
  std::vector<FrameRecord> frames_;
  std::map<int64_t, KeyframeRecord> keyframes_;  // by kf_id, every keyframe of the run
  std::vector<MapPoint> map_points_;             // points that left the window (marginalised)
  std::vector<int64_t> point_host_;              // per map point: its host keyframe's kf_id
  int64_t settled_t_ns_ = 0;                     // the scale is used for the outputs from then on
  // The transform a pose is mapped to W_m with (see the outputs): the current gravity rotation and
  // the scale of r's record or of the first after it made once the scale settled (r null: the first
  // such record of all), else the current transform.
  RxSO3d transformOf(const KeyframeRecord* r) const;
  // Map points (W_f) -> W_m with their host keyframe's transform; points and point_host_ index alike.
  void toMetric(std::vector<MapPoint>* points) const;
  RxSO3d currentTransform() const { return globals_->state.T_wm_wf; }
  DiagnosticsLog diag_;
  bool keep_photometric_ = false;
  bool provisional_ = false;
  std::vector<ObservationRow> photometric_rows_;
  StageTimes stages_;
  std::vector<std::string> warnings_;
};

}  // namespace rsvio
