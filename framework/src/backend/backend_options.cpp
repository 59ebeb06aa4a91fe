// The "backend" section: parameter table, reading and cross-field checks (contract in backend_options.h).
#include "rsvio/backend/backend_options.h"

#include <sstream>

#include "rsvio/config/validate.h"
#include "rsvio/core/error.h"

namespace rsvio {

ParamTable backendParamTable() {
  const BackendOptions d;
  return {
      paramInt("max_keyframes", d.max_keyframes, 2, 64, "", "keyframes in the optimisation window (DSO: 7)"),
      paramInt("min_keyframes", d.min_keyframes, 2, 64, "",
               "keyframes kept at least when marginalising by the point/brightness tests (DSO: 5)"),
      paramInt("active_points", d.active_points, 10, 100000, "", "target number of active points in the window"),
      paramInt("max_iterations", d.max_iterations, 1, 100, "", "Levenberg-Marquardt iterations per new keyframe"),
      paramInt("line_delay_hold_keyframes", d.line_delay_hold_keyframes, 2, 100000, "",
               "an estimated line delay (shutter.rolling estimate_line_delay) is held at its start until the run "
               "has made this many keyframes"),
      paramDouble("lambda_initial", d.lambda_initial, 0.0, 1e6, "", "initial relative LM damping"),
      paramDouble("step_threshold", d.step_threshold, 0.0, 1.0, "",
                  "stop iterating when the relative energy decrease is below this"),
      paramInt("max_rejected_steps", d.max_rejected_steps, 0, 100, "",
               "stop iterating after this many rejected Levenberg-Marquardt steps in a row (0: no such stop; "
               "docs/performance.md, Rejected steps)"),
      paramBool("accept_all_steps", d.accept_all_steps,
                "take every Levenberg-Marquardt step, also one that raises the energy (DSO's setting_forceAceptStep); "
                "the iterations then end on max_iterations or min_step_rad only"),
      paramBool("host_blocks_from_adjoint", d.host_blocks_from_adjoint,
                "rolling shutter: form each host pose's normal-equation blocks from its targets' through the pair's "
                "adjoint (false: accumulate every observation's own host-pose Jacobian, the slower reference; the "
                "same system to rounding; docs/rolling_shutter.md, Cost)"),
      paramDouble("min_step_rad", d.min_step_rad, 0.0, 1.0, "rad",
                  "stop iterating after an accepted step whose RMS keyframe rotation and RMS translation x mean "
                  "inverse depth are both below this (DSO's test, 6e-5 there) and whose inverse-depth steps are "
                  "below min_step_idepth (0: no such stop; docs/performance.md, Small steps)"),
      paramDouble("min_step_idepth", d.min_step_idepth, 0.0, 1.0, "",
                  "the small-step stop's bound on the points' RMS inverse-depth step, relative to their mean "
                  "inverse depth"),
      paramDouble("marg_weight_factor", d.marg_weight_factor, 0.0, 1.0, "",
                  "factor on the information of marginalised points (DSO: 0.25)"),
      paramBool("marg_project_scale", d.marg_project_scale,
                "project the monocular scale direction at the prior's linearisation points off the terms of "
                "marginalised points, so the prior keeps it as a null direction (FEJ consistency; docs/backend.md)"),
      paramDouble("min_idepth_hessian_marg", d.min_idepth_hessian_marg, 0.0, 1e12, "1/idepth^2",
                  "inverse-depth information a leaving point needs to enter the prior (DSO: 50)"),
      paramInt("min_good_residuals", d.min_good_residuals, 1, 64, "",
               "inlier observations a point needs to be kept and marginalised (DSO: 3)"),
      paramDouble("twist_regularization", d.twist_regularization, 0.0, 1e12, "s^2",
                  "information pulling a rolling-shutter twist to its start value when no motion prior gives one"),
      paramDouble("kf_weight_t", d.kf_weight_t, 0.0, 1e6, "", "keyframe score weight of the translation-only flow"),
      paramDouble("kf_weight_rt", d.kf_weight_rt, 0.0, 1e6, "", "keyframe score weight of the full flow"),
      paramDouble("kf_weight_affine", d.kf_weight_affine, 0.0, 1e6, "",
                  "keyframe score weight of |log brightness ratio|"),
      paramDouble("kf_rmse_factor", d.kf_rmse_factor, 1.0, 1e6, "",
                  "new keyframe when the tracking RMSE exceeds this times the first one after the last keyframe"),
      paramDouble("kf_max_interval_s", d.kf_max_interval_s, 0.0, 1e6, "s",
                  "a new keyframe at least this often (0: off)"),
      paramDouble("kf_flow_scale", d.kf_flow_scale, 0.0, 1e6, "",
                  "both flow weights (kf_weight_t, kf_weight_rt) times this once the run has kf_start_keyframes "
                  "keyframes (DSO's setting_kfGlobalWeight; < 1: fewer keyframes)"),
      paramInt("kf_start_keyframes", d.kf_start_keyframes, 0, 1000000, "",
               "the run's first keyframes, made with the flow weights unscaled (the start's depths need them close)"),
      paramDouble("min_points_remaining", d.min_points_remaining, 0.0, 1.0, "",
                  "marginalise a keyframe when fewer than this share of its points remain (DSO: 0.05)"),
      paramDouble("max_log_affine", d.max_log_affine, 0.0, 100.0, "",
                  "marginalise a keyframe whose brightness ratio to the newest exceeds exp(this) (DSO: 0.7)"),
      paramInt("activation_iterations", d.activation_iterations, 0, 50, "",
               "Gauss-Newton iterations on a candidate's inverse depth against the window before activation"),
      paramDouble("activation_min_dist_px", d.activation_min_dist_px, 0.0, 4.0, "px",
                  "initial distance between active points on pyramid level 1; adapted towards active_points"),
      paramDouble("activation_min_idepth_hessian", d.activation_min_idepth_hessian, 0.0, 1e9, "",
                  "information on a candidate's inverse depth after its activation steps below which it is dropped "
                  "(DSO setting_minIdepthH_act)"),
      paramInt("init_min_frames", d.init_min_frames, 1, 1000, "", "frames after the first before initialising"),
      paramInt("init_max_frames", d.init_max_frames, 2, 100000, "",
               "frames without a successful monocular initialisation before the run fails"),
      paramDouble("init_min_flow_px", d.init_min_flow_px, 0.0, 1.0, "",
                  "median corner flow before an initialisation attempt, as a fraction of the image diagonal"),
      paramDouble("init_min_parallax_deg", d.init_min_parallax_deg, 0.0, 90.0, "deg",
                  "median triangulation angle needed to initialise"),
      paramDouble("init_min_inlier_ratio", d.init_min_inlier_ratio, 0.0, 1.0, "",
                  "share of corner tracks consistent with the essential matrix"),
      paramInt("init_corners", d.init_corners, 20, 10000, "", "corners tracked during initialisation"),
      paramInt("init_rolling_shutter_iterations", d.init_rolling_shutter_iterations, 0, 20, "",
               "rolling shutter: rounds of the two-view start that move each corner to its image's central pose "
               "(0: the start ignores the readout)"),
      paramBool("init_keyframe_twist", d.init_keyframe_twist,
                "rolling shutter: the first keyframe starts with the two-view start's twist (else 0)"),
      paramDouble("init_affine_min_change", d.init_affine_min_change, 0.0, 100.0, "",
                  "with affine brightness estimated: the second keyframe starts with the gain of the start's corners "
                  "against the first when it differs from 1 by more than this (else a = b = 0; 0: always)"),
      paramBool("init_rotation_rates", d.init_rotation_rates,
                "rolling shutter: the two-view start rotates each image's corners to its central pose with the "
                "image's own rotation rate, measured from its neighbour frames, and the first two keyframes "
                "start with those rates (off: the readout is ignored or init_rolling_shutter_iterations)"),
      paramInt("max_lost_frames", d.max_lost_frames, 0, 1000, "",
               "consecutive frames the tracker may lose before the run fails"),
      paramDouble("fail_max_rmse", d.fail_max_rmse, 0.0, 1e6, "intensity",
                  "the run fails when the window's photometric RMSE exceeds this"),
      paramDouble("fail_min_inlier_ratio", d.fail_min_inlier_ratio, 0.0, 1.0, "",
                  "the run fails when fewer observations than this share are inliers"),
      paramInt("fail_min_points", d.fail_min_points, 0, 100000, "",
               "the run fails when fewer active points remain after a keyframe's optimisation"),
      paramDouble("fail_max_scale_change", d.fail_max_scale_change, 1.0, 1e12, "",
                  "the run fails when the median inverse depth changes by more than this factor (scale collapse)"),
  };
}

BackendOptions BackendOptions::fromParams(const Params& p) {
  BackendOptions o;
  o.max_keyframes = static_cast<int>(p.getInt("max_keyframes"));
  o.min_keyframes = static_cast<int>(p.getInt("min_keyframes"));
  o.active_points = static_cast<int>(p.getInt("active_points"));
  o.max_iterations = static_cast<int>(p.getInt("max_iterations"));
  o.line_delay_hold_keyframes = static_cast<int>(p.getInt("line_delay_hold_keyframes"));
  o.lambda_initial = p.getDouble("lambda_initial");
  o.step_threshold = p.getDouble("step_threshold");
  o.max_rejected_steps = static_cast<int>(p.getInt("max_rejected_steps"));
  o.accept_all_steps = p.getBool("accept_all_steps");
  o.host_blocks_from_adjoint = p.getBool("host_blocks_from_adjoint");
  o.min_step_rad = p.getDouble("min_step_rad");
  o.min_step_idepth = p.getDouble("min_step_idepth");
  o.marg_weight_factor = p.getDouble("marg_weight_factor");
  o.marg_project_scale = p.getBool("marg_project_scale");
  o.min_idepth_hessian_marg = p.getDouble("min_idepth_hessian_marg");
  o.min_good_residuals = static_cast<int>(p.getInt("min_good_residuals"));
  o.twist_regularization = p.getDouble("twist_regularization");
  o.kf_weight_t = p.getDouble("kf_weight_t");
  o.kf_weight_rt = p.getDouble("kf_weight_rt");
  o.kf_weight_affine = p.getDouble("kf_weight_affine");
  o.kf_rmse_factor = p.getDouble("kf_rmse_factor");
  o.kf_max_interval_s = p.getDouble("kf_max_interval_s");
  o.kf_flow_scale = p.getDouble("kf_flow_scale");
  o.kf_start_keyframes = static_cast<int>(p.getInt("kf_start_keyframes"));
  o.min_points_remaining = p.getDouble("min_points_remaining");
  o.max_log_affine = p.getDouble("max_log_affine");
  o.activation_iterations = static_cast<int>(p.getInt("activation_iterations"));
  o.activation_min_dist_px = p.getDouble("activation_min_dist_px");
  o.activation_min_idepth_hessian = p.getDouble("activation_min_idepth_hessian");
  o.init_min_frames = static_cast<int>(p.getInt("init_min_frames"));
  o.init_max_frames = static_cast<int>(p.getInt("init_max_frames"));
  o.init_min_flow_px = p.getDouble("init_min_flow_px");
  o.init_min_parallax_deg = p.getDouble("init_min_parallax_deg");
  o.init_min_inlier_ratio = p.getDouble("init_min_inlier_ratio");
  o.init_corners = static_cast<int>(p.getInt("init_corners"));
  o.init_rolling_shutter_iterations = static_cast<int>(p.getInt("init_rolling_shutter_iterations"));
  o.init_keyframe_twist = p.getBool("init_keyframe_twist");
  o.init_affine_min_change = p.getDouble("init_affine_min_change");
  o.init_rotation_rates = p.getBool("init_rotation_rates");
  o.max_lost_frames = static_cast<int>(p.getInt("max_lost_frames"));
  o.fail_max_rmse = p.getDouble("fail_max_rmse");
  o.fail_min_inlier_ratio = p.getDouble("fail_min_inlier_ratio");
  o.fail_min_points = static_cast<int>(p.getInt("fail_min_points"));
  o.fail_max_scale_change = p.getDouble("fail_max_scale_change");
  o.validate();
  return o;
}

void BackendOptions::validate() const {
  std::ostringstream os;
  if (min_keyframes > max_keyframes)
    os << "backend.min_keyframes = " << min_keyframes << ". Violated constraint: min_keyframes <= max_keyframes ("
       << max_keyframes << ")";
  else if (init_min_frames >= init_max_frames)
    os << "backend.init_min_frames = " << init_min_frames
       << ". Violated constraint: init_min_frames < init_max_frames (" << init_max_frames << ")";
  if (!os.str().empty()) throw ConfigError(os.str());
}

BackendOptions backendOptionsFromConfig(const nlohmann::json& effective_config) {
  return BackendOptions::fromParams(sectionParams(effective_config, "backend", backendParamTable()));
}

}  // namespace rsvio
