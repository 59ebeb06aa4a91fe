// The estimator as `rsvio run` drives it: one object per run, built from a validated run config
// (config/validate.h: runConfigSchema) and the data source's sensors; fed IMU samples and frames in
// time order; asked for results at the end. It never reads ground truth.
//
// Contract
// - Frames arrive in order; before addFrame(f), every IMU sample with t_imu <= f.t_ns + time offset
//   (+ the frame's readout) has been given to addImu (the run loop guarantees it).
// - World: VO: the first keyframe's camera frame, free scale ("# frame: camera" outputs);
//   VIO: the metric world W_m, z up, after initialisation ("# frame: body" outputs, stamped on the IMU
//   clock t_cam + time offset).
// - status(): "ok" while running; after a divergence (exploding energy, scale collapse, too few
//   inliers, tracking lost without recovery) "failed" with a one-line reason. Once failed, further
//   frames are ignored; what was estimated before the failure stays available.
// - Determinism: the same config, seed, data and thread count give bit-identical results.
// - Thread use: at most config "threads" threads.
#pragma once
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "rsvio/core/types.h"
#include "rsvio/io/diagnostics_log.h"
#include "rsvio/io/states.h"
#include "rsvio/io/trajectory.h"

namespace rsvio {

class PluginHost;

struct MapPoint {
  Eigen::Vector3f p_w;      // world frame (W_f for VO, W_m for VIO)
  float intensity = 0.f;    // host intensity
};

struct FrameStatus {
  bool tracked = false;
  bool keyframe = false;
  std::string message;      // e.g. "initialising", "tracking lost: too few inliers"
};

class Odometry {
 public:
  // effective_config: validated against runConfigSchema(); seed overrides config "seed".
  Odometry(const nlohmann::json& effective_config, PluginHost& host, const SensorSetup& sensors);
  ~Odometry();
  Odometry(const Odometry&) = delete;
  Odometry& operator=(const Odometry&) = delete;

  void addImu(const ImuSample& sample);
  FrameStatus addFrame(const Frame& frame);
  // Final optimisation; marginalises everything so the diagnostics log holds final linearisations.
  void finish();

  bool failed() const;
  std::string failureReason() const;

  // Results (valid any time; complete after finish()).
  io::Trajectory frameTrajectory() const;     // every tracked frame, refined (conventions.md, Outputs)
  io::Trajectory keyframeTrajectory() const;  // keyframes after their last optimisation
  std::vector<MapPoint> points() const;  // those not taken by takePoints(), then the window's
  // Appends the points that left the window so far to *points and forgets them (as takeDiagnostics).
  void takePoints(std::vector<MapPoint>* points);
  std::vector<StateRow> states() const;
  // The diagnostics log: image size, line delay, IMU rows, and the observation rows made since the last
  // takeDiagnostics() (every row of the run when it is never called).
  const DiagnosticsLog& diagnostics() const;
  // Appends the observation rows made so far to *rows and forgets them: the run loop streams them to
  // diagnostics.bin as the run goes (pipeline/run.cpp), so a long run's memory stays flat.
  void takeDiagnostics(std::vector<ObservationRow>* rows);
  std::map<std::string, double> stageMs() const;  // mean ms per call of each stage
  long numKeyframes() const;
  bool usesImu() const;
  double scale() const;                            // metres per W_f unit (1 without IMU)
  // Visual-inertial runs: {"initialised", "status" (why not, or how), "initialised_at_s", "scale",
  // "scale_at_initialisation", "gravity_direction_wf", "time_offset_ms", "time_offset_estimated",
  // "init_refusals" and, after a refusal, "init_first_refusal_at_s", "init_first_refusal"};
  // null for visual odometry. usesImu() is true once initialised.
  nlohmann::json inertialReport() const;
  // Rolling shutter (null for a global shutter): the line delay the run ended with, whether it was
  // estimated online and where the estimate started (report.json "shutter").
  nlohmann::json shutterReport() const;
  // Photometric models estimated online (photometric.vignette without a calibration): each slot's final
  // parameters and every refinement (frame, parameters, what changed); null without one.
  nlohmann::json photometricReport() const;
  std::vector<std::string> warnings() const;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace rsvio
