// Options of the photometric back end (windowed bundle adjustment, keyframes, points, marginalisation,
// monocular initialisation, divergence detection): the "backend" section of a run config.
//
// Defaults follow DSO (Engel et al. 2018; its settings.cpp values are named where they differ in
// meaning): 7 keyframes, ~2000 active points, 6 LM iterations per keyframe, marginalisation when fewer
// than 5 % of a keyframe's points remain or its brightness drifted by more than exp(0.7), otherwise
// the keyframe with the largest distance score. backendParamTable() is the one table that validation,
// `rsvio plugins`-style listings and docs/backend.md use.
#pragma once
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "rsvio/plugin/plugin.h"

namespace rsvio {

struct BackendOptions {
  // Window and points.
  int max_keyframes = 7;              // DSO setting_maxFrames
  int min_keyframes = 5;              // DSO setting_minFrames: never marginalise below this by the point test
  int active_points = 2000;           // target number of active points in the window (DSO desiredPointDensity)
  // Optimisation.
  int max_iterations = 6;             // LM iterations per new keyframe (DSO setting_maxOptIterations)
  double lambda_initial = 1e-4;       // relative diagonal damping, H_ii *= (1 + lambda)
  double step_threshold = 1e-4;       // stop when the relative energy decrease is below this
  int max_rejected_steps = 0;         // stop after this many rejected steps in a row (0: no such stop)
  bool accept_all_steps = false;      // take every step (DSO setting_forceAceptStep)
  bool host_blocks_from_adjoint = true;  // rolling shutter: host-pose blocks from the target's (same energy)
  double min_step_rad = 0.0;          // stop after an accepted step whose pose steps are this small (DSO: 6e-5;
                                      // 0: no such stop) ...
  double min_step_idepth = 0.01;      // ... and whose RMS inverse-depth step is below this x their mean
  double marg_weight_factor = 0.25;   // Hessian factor of marginalised points (DSO setting_margWeightFac)
  bool marg_project_scale = true;     // project the scale direction at x_lin off marginalised points' terms
  double min_idepth_hessian_marg = 50.0;  // a point leaving the window goes into the prior above this (DSO)
  int min_good_residuals = 3;         // observations a point needs to be kept / marginalised (DSO: 3)
  double twist_regularization = 1e-6; // tiny information on twists without a prior (rolling shutter)
  int line_delay_hold_keyframes = 20; // an estimated line delay is held until the run has this many keyframes
  // Keyframe selection (DSO's weights; the flows are RMS pixel shifts normalised by width + height).
  double kf_weight_t = 0.04 * (640 + 480);   // translation-only flow
  double kf_weight_rt = 0.02 * (640 + 480);  // full flow
  double kf_weight_affine = 2.0;             // |log exposure ratio|
  double kf_rmse_factor = 2.0;               // new KF when rmse > factor x the first rmse after the last KF
  double kf_max_interval_s = 0.0;            // new KF at least this often (0 = off, DSO's default)
  double kf_flow_scale = 1.0;                // both flow weights times this (DSO's setting_kfGlobalWeight) ...
  int kf_start_keyframes = 0;                // ... once the run has this many keyframes (before: times 1)
  // Marginalisation of keyframes.
  double min_points_remaining = 0.05;  // DSO setting_minPointsRemaining
  double max_log_affine = 0.7;         // DSO setting_maxLogAffFacInWindow
  // Candidate activation (which candidates are ready: the front end's trace_* options).
  int activation_iterations = 3;            // GN iterations on a candidate's inverse depth (DSO: 3)
  double activation_min_dist_px = 2.0;      // initial distance between active points, level-1 px (DSO: 2)
  double activation_min_idepth_hessian = 100.0;  // dropped below this after activation (DSO setting_minIdepthH_act)
  // Monocular initialisation (runs without an IMU).
  int init_min_frames = 3;            // frames after the first before an attempt
  int init_max_frames = 60;           // give up (status failed) after this many frames
  double init_min_flow_px = 0.025;    // median corner flow, fraction of the image diagonal
  double init_min_parallax_deg = 1.0; // median triangulation angle of the inlier corners
  double init_min_inlier_ratio = 0.6; // essential-matrix RANSAC inliers
  int init_corners = 400;             // corners tracked with pyramidal Lucas-Kanade
  int init_rolling_shutter_iterations = 0;  // two-view rounds with the corners at their row times (mono_initializer.h)
  bool init_keyframe_twist = false;   // rolling shutter: keyframe 0 starts with the two-view twist
  // Affine brightness estimated: keyframe 1 starts with the start corners' gain g against keyframe 0
  // (mono_initializer.h, logGainCurRef) when |g - 1| exceeds this. 0.1: a uniform change of 10 % at
  // mid-grey (13 grey levels) reaches the candidates' trace's outlier energy (DSO's 12^2 per pixel,
  // Huber 9, slack 1.2); below it the trace copes and the guess would only perturb the start.
  double init_affine_min_change = 0.1;
  bool init_rotation_rates = true;    // rolling shutter: each start image's rotation rate from its
                                      // neighbour frames (mono_initializer.h); the keyframes start with it
  // Divergence detection (the run ends "failed" with the reason).
  int max_lost_frames = 3;            // consecutive frames the tracker loses
  double fail_max_rmse = 40.0;        // BA RMSE per pattern pixel, intensity units
  double fail_min_inlier_ratio = 0.3; // BA inlier observations / all
  int fail_min_points = 20;           // active points after a keyframe's BA
  double fail_max_scale_change = 50.0;  // median inverse depth vs. the initial one, either way

  void validate() const;  // cross-field checks; throws ConfigError naming the keys
  static BackendOptions fromParams(const Params& p);
};

// The "backend" section's table (keys as the fields above).
ParamTable backendParamTable();

// Reads the "backend" section of an effective config with defaults filled in; problems (wrong type,
// unknown key) throw ConfigError listing each with its JSON path.
BackendOptions backendOptionsFromConfig(const nlohmann::json& effective_config);

}  // namespace rsvio
