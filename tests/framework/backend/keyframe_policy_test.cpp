// Keyframe policy (rsvio/backend/keyframe_policy.h: needKeyframe, keyframesToMarginalize) and the
// backend options (rsvio/backend/backend_options.h). A policy that made every frame a keyframe, never
// made one, marginalised the newest or the run's first keyframe by the distance score, or let the window
// overflow fails here; so does a backend key that is in the table but not read into BackendOptions.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <string>

#include "rsvio/backend/backend_options.h"
#include "rsvio/backend/keyframe_policy.h"
#include "rsvio/core/error.h"
#include "support/param_table_check.h"

namespace rsvio {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A tracked frame at 640x512 with the given flows (px), log brightness ratio and RMSEs.
KeyframeCue cue(double flow_t, double flow_rt, double log_ab = 0.0, double rmse = 5.0, double first_rmse = 5.0,
                double seconds = 0.05) {
  KeyframeCue c;
  c.flow_t_px = flow_t;
  c.flow_rt_px = flow_rt;
  c.log_brightness_ratio = log_ab;
  c.rmse = rmse;
  c.first_rmse = first_rmse;
  c.seconds_since_keyframe = seconds;
  c.width = 640;
  c.height = 512;
  return c;
}

TEST(KeyframePolicy, NoMotionNeedsNoKeyframe) {
  const BackendOptions o;
  std::string why = "unchanged";
  EXPECT_FALSE(needKeyframe(o, cue(0.0, 0.0), &why));
  EXPECT_EQ(why, "unchanged");  // the reason is only written when a keyframe is needed
  EXPECT_FALSE(needKeyframe(o, cue(0.0, 0.0, 0.0, 5.0, kNaN)));
  // A typical frame 50 ms after a keyframe at medium motion: a few pixels of flow.
  EXPECT_FALSE(needKeyframe(o, cue(3.0, 8.0, 0.02, 6.0, 5.5)));
}

TEST(KeyframePolicy, TranslationFlowThreshold) {
  // DSO's weights: 0.04 (640 + 480) per px of translation-only flow, normalised by w + h = 1152, so the
  // threshold is 1152 / 44.8 = 25.7 px of translation flow alone.
  const BackendOptions o;
  const double th = (640 + 512) / o.kf_weight_t;
  EXPECT_NEAR(th, 25.714, 1e-3);
  std::string why;
  EXPECT_FALSE(needKeyframe(o, cue(0.98 * th, 0.0), &why));
  EXPECT_TRUE(needKeyframe(o, cue(1.02 * th, 0.0), &why));
  EXPECT_EQ(why, "flow");
}

TEST(KeyframePolicy, RotationFlowThreshold) {
  // The full flow (rotation included) weighs half: 51.4 px alone.
  const BackendOptions o;
  const double th = (640 + 512) / o.kf_weight_rt;
  std::string why;
  EXPECT_FALSE(needKeyframe(o, cue(0.0, 0.98 * th), &why));
  EXPECT_TRUE(needKeyframe(o, cue(0.0, 1.02 * th), &why));
  EXPECT_EQ(why, "flow");
  // The two flows add: 60 % of each threshold together exceed 1.
  EXPECT_TRUE(needKeyframe(o, cue(0.6 * (640 + 512) / o.kf_weight_t, 0.6 * th), &why));
}

TEST(KeyframePolicy, ScoreIsNormalisedByTheImageSize) {
  // The same pixel flow on an image four times as large (w + h doubled) is half the score.
  const BackendOptions o;
  KeyframeCue c = cue(30.0, 0.0);
  EXPECT_TRUE(needKeyframe(o, c));
  c.width = 1280;
  c.height = 1024;
  EXPECT_FALSE(needKeyframe(o, c));
}

TEST(KeyframePolicy, BrightnessChange) {
  // kf_weight_affine 2: |log a| above 0.5 alone makes a keyframe; with some flow, less is enough.
  const BackendOptions o;
  std::string why;
  EXPECT_FALSE(needKeyframe(o, cue(0.0, 0.0, 0.45), &why));
  EXPECT_TRUE(needKeyframe(o, cue(0.0, 0.0, 0.55), &why));
  EXPECT_EQ(why, "brightness");
  EXPECT_TRUE(needKeyframe(o, cue(0.0, 0.0, -0.55), &why));  // darker as brighter
  EXPECT_TRUE(needKeyframe(o, cue(13.0, 0.0, 0.3), &why));    // 0.51 + 0.6
  EXPECT_EQ(why, "flow and brightness");
}

TEST(KeyframePolicy, TrackingRmseAgainstTheFirstAfterTheKeyframe) {
  const BackendOptions o;  // kf_rmse_factor 2
  std::string why;
  EXPECT_FALSE(needKeyframe(o, cue(1.0, 1.0, 0.0, 9.9, 5.0), &why));
  EXPECT_TRUE(needKeyframe(o, cue(1.0, 1.0, 0.0, 10.1, 5.0), &why));
  EXPECT_EQ(why, "rmse");
  // No first RMSE yet (the first frame after a keyframe): no RMSE test.
  EXPECT_FALSE(needKeyframe(o, cue(1.0, 1.0, 0.0, 100.0, kNaN)));
  EXPECT_FALSE(needKeyframe(o, cue(1.0, 1.0, 0.0, 100.0, 0.0)));
}

TEST(KeyframePolicy, MaxIntervalOnlyWhenSwitchedOn) {
  BackendOptions o;
  EXPECT_EQ(o.kf_max_interval_s, 0.0);  // DSO: off
  EXPECT_FALSE(needKeyframe(o, cue(0.0, 0.0, 0.0, 5.0, 5.0, 100.0)));
  o.kf_max_interval_s = 0.5;
  std::string why;
  EXPECT_FALSE(needKeyframe(o, cue(0.0, 0.0, 0.0, 5.0, 5.0, 0.45), &why));
  EXPECT_TRUE(needKeyframe(o, cue(0.0, 0.0, 0.0, 5.0, 5.0, 0.5), &why));
  EXPECT_EQ(why, "interval");
}

TEST(KeyframePolicy, KeyframeRateOnASteadyMotion) {
  // A camera moving steadily so that each frame adds 4 px of translation flow and 6 px of full flow to
  // the reference keyframe's: the flows since the keyframe grow linearly, and a keyframe follows when
  // 44.8 * 4 k / 1152 + 22.4 * 6 k / 1152 > 1, i.e. at k = 4. Over 100 frames: 25 keyframes, not 100
  // (every frame) and not 0.
  const BackendOptions o;
  int keyframes = 0, since = 0;
  for (int f = 0; f < 100; ++f) {
    ++since;
    if (needKeyframe(o, cue(4.0 * since, 6.0 * since, 0.0, 5.0, 5.0, 0.05 * since))) {
      ++keyframes;
      since = 0;
    }
  }
  EXPECT_EQ(keyframes, 25);
}

// The flow weights scaled (kf_flow_scale, DSO's setting_kfGlobalWeight) once the run has
// kf_start_keyframes keyframes: on the steady motion above a keyframe every 4 frames with DSO's
// weights; with the scale 0.5, every 8 (0.5 (44.8 * 4 k + 22.4 * 6 k) / 1152 > 1 at k = 8): 12 over
// 100 frames; with the run's first 7 keyframes unscaled (the first came before frame 0), 6 more every 4
// frames, then every 8: 6 + 9 = 15. Fails when the scale is ignored (25) or applied from the start (12;
// shown once).
TEST(KeyframePolicy, FlowScaleAppliesOnceTheRunHasItsStartKeyframes) {
  BackendOptions o;
  EXPECT_EQ(o.kf_flow_scale, 1.0);  // DSO: 1
  EXPECT_EQ(o.kf_start_keyframes, 0);
  auto count = [](const BackendOptions& opt) {
    int keyframes = 0, since = 0;
    for (int f = 0; f < 100; ++f) {
      ++since;
      KeyframeCue c = cue(4.0 * since, 6.0 * since, 0.0, 5.0, 5.0, 0.05 * since);
      c.keyframes = 1 + keyframes;  // the run's first keyframe came before frame 0
      if (needKeyframe(opt, c)) {
        ++keyframes;
        since = 0;
      }
    }
    return keyframes;
  };
  EXPECT_EQ(count(o), 25);
  o.kf_flow_scale = 0.5;
  EXPECT_EQ(count(o), 12);
  o.kf_start_keyframes = 7;
  EXPECT_EQ(count(o), 15);
  // One cue on either side of the start: 1.5x the translation threshold alone.
  KeyframeCue c = cue(1.5 * (640 + 512) / o.kf_weight_t, 0.0);
  c.keyframes = 6;
  std::string why;
  EXPECT_TRUE(needKeyframe(o, c, &why));
  EXPECT_EQ(why, "flow");
  c.keyframes = 7;
  EXPECT_FALSE(needKeyframe(o, c));
}

// ---- keyframesToMarginalize

struct Window {
  KeyframeList kfs;
  // A keyframe with its camera centre at (x, 0, 0), `in` points still in (active + candidates), `out` gone.
  Keyframe* add(double x, int in = 100, int out = 0, double a = 0.0) {
    auto kf = std::make_unique<Keyframe>();
    kf->kf_id = static_cast<int64_t>(kfs.size());
    kf->frame_index = 3 * kf->kf_id;
    kf->state.T_c_w = SE3d(SO3d(), Vec3(-x, 0.0, 0.0));  // centre = -R^T t = (x, 0, 0)
    kf->state.affine.a = a;
    kf->points.resize(static_cast<size_t>(in / 2));
    kf->candidates.resize(static_cast<size_t>(in - in / 2));
    kf->points_out = out;
    kfs.push_back(std::move(kf));
    reindex(kfs);
    return kfs.back().get();
  }
};

std::vector<int64_t> ids(const std::vector<Keyframe*>& v) {
  std::vector<int64_t> out;
  for (const Keyframe* k : v) out.push_back(k->kf_id);
  return out;
}

TEST(KeyframeMarginalization, NothingBeforeTheWindowIsFull) {
  const BackendOptions o;  // 7 keyframes
  Window w;
  for (int i = 0; i < 6; ++i) w.add(i);
  EXPECT_TRUE(keyframesToMarginalize(w.kfs, o, 0).empty());
  EXPECT_TRUE(keyframesToMarginalize(KeyframeList(), o, 0).empty());
}

TEST(KeyframeMarginalization, FullWindowLosesTheKeyframeWithTheLargestDistanceScore) {
  // Centres 0, 1, 2, 2.05, 4, 5, 6 (newest): the pair at 2 and 2.05 is redundant; the score
  // sqrt(d(i, newest)) sum_j 1 / (d(i, j) + 1e-5) is 45.16 for x = 2 and 44.80 for x = 2.05.
  const BackendOptions o;
  Window w;
  for (double x : {0.0, 1.0, 2.0, 2.05, 4.0, 5.0, 6.0}) w.add(x);
  const auto out = keyframesToMarginalize(w.kfs, o, 0);
  EXPECT_EQ(ids(out), (std::vector<int64_t>{2}));
  EXPECT_TRUE(w.kfs[2]->flagged_for_marg);
  for (int i : {0, 1, 3, 4, 5, 6}) EXPECT_FALSE(w.kfs[static_cast<size_t>(i)]->flagged_for_marg);
}

TEST(KeyframeMarginalization, NeverTheNewestNorTheFirstByDistance) {
  // The first keyframe (x = 0) and its twin at 0.01 score highest; the first is kept, its twin goes.
  // The newest has distance 0 to itself and is never a candidate either.
  const BackendOptions o;
  Window w;
  for (double x : {0.0, 0.01, 2.0, 3.0, 4.0, 5.0, 6.0}) w.add(x);
  EXPECT_EQ(ids(keyframesToMarginalize(w.kfs, o, 0)), (std::vector<int64_t>{1}));
  // Had the run started with the keyframe at 0.01 (first_kf_id 1), the one at 0 goes.
  EXPECT_EQ(ids(keyframesToMarginalize(w.kfs, o, 1)), (std::vector<int64_t>{0}));
}

TEST(KeyframeMarginalization, KeyframeWithFewPointsLeftGoesEvenBeforeTheWindowIsFull) {
  // 4 of 100 points left (< 5 %): flagged; 6 of 100: kept.
  const BackendOptions o;
  Window w;
  w.add(0);
  w.add(1, 4, 96);
  w.add(2, 6, 94);
  w.add(3);
  w.add(4);
  w.add(5);
  EXPECT_EQ(ids(keyframesToMarginalize(w.kfs, o, 0)), (std::vector<int64_t>{1}));
}

TEST(KeyframeMarginalization, PointAndBrightnessTestsKeepMinKeyframes) {
  // Every keyframe but the newest has lost its points, yet at least min_keyframes (5) stay.
  const BackendOptions o;
  Window w;
  for (int i = 0; i < 6; ++i) w.add(i, 1, 99);
  w.add(6);
  const auto out = keyframesToMarginalize(w.kfs, o, 0);
  EXPECT_EQ(out.size(), 2u);
  EXPECT_EQ(ids(out), (std::vector<int64_t>{0, 1}));  // oldest first
  // A window of exactly min_keyframes loses nothing by the point test.
  Window small;
  for (int i = 0; i < 4; ++i) small.add(i, 1, 99);
  small.add(4);
  EXPECT_TRUE(keyframesToMarginalize(small.kfs, o, 0).empty());
}

TEST(KeyframeMarginalization, BrightnessDriftedKeyframeGoes) {
  // |log ratio to the newest| 0.8 > 0.7: flagged; 0.6: kept.
  const BackendOptions o;
  Window w;
  w.add(0, 100, 0, 0.0);
  w.add(1, 100, 0, -0.8);
  w.add(2, 100, 0, 0.6);
  w.add(3, 100, 0, 0.0);
  w.add(4, 100, 0, 0.0);
  w.add(5, 100, 0, 0.0);
  EXPECT_EQ(ids(keyframesToMarginalize(w.kfs, o, 0)), (std::vector<int64_t>{1}));
}

TEST(KeyframeMarginalization, WindowNeverOverflows) {
  // Whatever the geometry, a full window gives up at least one keyframe, and never the newest; with
  // only the first and the newest left to choose (max_keyframes 2), the first goes.
  BackendOptions o;
  for (int n = 7; n <= 9; ++n) {
    Window w;
    for (int i = 0; i < n; ++i) w.add(0.0);  // all centres equal: scores 0
    const auto out = keyframesToMarginalize(w.kfs, o, 0);
    ASSERT_FALSE(out.empty()) << n;
    for (const Keyframe* k : out) EXPECT_NE(k, w.kfs.back().get());
  }
  o.max_keyframes = 2;
  o.min_keyframes = 2;
  Window two;
  two.add(0);
  two.add(1);
  EXPECT_EQ(ids(keyframesToMarginalize(two.kfs, o, 0)), (std::vector<int64_t>{0}));
}

TEST(KeyframeMarginalization, ClearsOldFlags) {
  const BackendOptions o;
  Window w;
  for (int i = 0; i < 6; ++i) w.add(i);
  for (auto& k : w.kfs) k->flagged_for_marg = true;
  EXPECT_TRUE(keyframesToMarginalize(w.kfs, o, 0).empty());
  for (auto& k : w.kfs) EXPECT_FALSE(k->flagged_for_marg);
}

TEST(LogBrightnessRatio, ExposureAndAffine) {
  AffineBrightness a, b;
  a.a = 0.1;
  b.a = 0.3;
  EXPECT_NEAR(logBrightnessRatio(a, kNaN, b, kNaN), 0.2, 1e-12);
  EXPECT_NEAR(logBrightnessRatio(a, 10.0, b, 20.0), std::log(2.0) + 0.2, 1e-12);
  EXPECT_NEAR(logBrightnessRatio(a, 0.0, b, 20.0), 0.2, 1e-12);  // unknown exposure: ratio 1
}

// ---- backend options

TEST(BackendOptions, DefaultsAreDsos) {
  const BackendOptions o = backendOptionsFromConfig(nlohmann::json::object());
  EXPECT_EQ(o.max_keyframes, 7);
  EXPECT_EQ(o.min_keyframes, 5);
  EXPECT_EQ(o.active_points, 2000);
  EXPECT_EQ(o.max_iterations, 6);
  EXPECT_DOUBLE_EQ(o.kf_weight_t, 0.04 * (640 + 480));
  EXPECT_DOUBLE_EQ(o.kf_weight_rt, 0.02 * (640 + 480));
  EXPECT_DOUBLE_EQ(o.kf_weight_affine, 2.0);
  EXPECT_DOUBLE_EQ(o.kf_rmse_factor, 2.0);
  EXPECT_DOUBLE_EQ(o.min_points_remaining, 0.05);
  EXPECT_DOUBLE_EQ(o.max_log_affine, 0.7);
  EXPECT_DOUBLE_EQ(o.marg_weight_factor, 0.25);
  EXPECT_DOUBLE_EQ(o.min_idepth_hessian_marg, 50.0);
  EXPECT_EQ(o.min_good_residuals, 3);
  EXPECT_DOUBLE_EQ(o.activation_min_idepth_hessian, 100.0);
  // The table's defaults are the struct's.
  const BackendOptions d;
  EXPECT_EQ(o.max_keyframes, d.max_keyframes);
  EXPECT_EQ(o.init_max_frames, d.init_max_frames);
  EXPECT_EQ(o.fail_max_scale_change, d.fail_max_scale_change);
}

// Every key of the table, set to a value other than its default (inside its range), must reach the
// struct: a key that is listed but not read would leave a field at its default.
TEST(BackendOptions, EveryTableKeyIsRead) {
  const ParamTable table = backendParamTable();
  ASSERT_GE(table.size(), 30u);
  nlohmann::json sec = test::nonDefaultSection(table);
  // Keep the cross-field constraints satisfied.
  sec["min_keyframes"] = 6;
  sec["max_keyframes"] = 8;
  sec["init_min_frames"] = 4;
  sec["init_max_frames"] = 61;
  const BackendOptions o = backendOptionsFromConfig(nlohmann::json{{"backend", sec}});
  nlohmann::json got;
  got["max_keyframes"] = o.max_keyframes;
  got["min_keyframes"] = o.min_keyframes;
  got["active_points"] = o.active_points;
  got["max_iterations"] = o.max_iterations;
  got["line_delay_hold_keyframes"] = o.line_delay_hold_keyframes;
  got["lambda_initial"] = o.lambda_initial;
  got["step_threshold"] = o.step_threshold;
  got["max_rejected_steps"] = o.max_rejected_steps;
  got["accept_all_steps"] = o.accept_all_steps;
  got["host_blocks_from_adjoint"] = o.host_blocks_from_adjoint;
  got["min_step_rad"] = o.min_step_rad;
  got["min_step_idepth"] = o.min_step_idepth;
  got["marg_weight_factor"] = o.marg_weight_factor;
  got["marg_project_scale"] = o.marg_project_scale;
  got["min_idepth_hessian_marg"] = o.min_idepth_hessian_marg;
  got["min_good_residuals"] = o.min_good_residuals;
  got["twist_regularization"] = o.twist_regularization;
  got["kf_weight_t"] = o.kf_weight_t;
  got["kf_weight_rt"] = o.kf_weight_rt;
  got["kf_weight_affine"] = o.kf_weight_affine;
  got["kf_rmse_factor"] = o.kf_rmse_factor;
  got["kf_max_interval_s"] = o.kf_max_interval_s;
  got["kf_flow_scale"] = o.kf_flow_scale;
  got["kf_start_keyframes"] = o.kf_start_keyframes;
  got["min_points_remaining"] = o.min_points_remaining;
  got["max_log_affine"] = o.max_log_affine;
  got["activation_iterations"] = o.activation_iterations;
  got["activation_min_dist_px"] = o.activation_min_dist_px;
  got["activation_min_idepth_hessian"] = o.activation_min_idepth_hessian;
  got["init_min_frames"] = o.init_min_frames;
  got["init_max_frames"] = o.init_max_frames;
  got["init_min_flow_px"] = o.init_min_flow_px;
  got["init_min_parallax_deg"] = o.init_min_parallax_deg;
  got["init_min_inlier_ratio"] = o.init_min_inlier_ratio;
  got["init_corners"] = o.init_corners;
  got["init_rolling_shutter_iterations"] = o.init_rolling_shutter_iterations;
  got["init_keyframe_twist"] = o.init_keyframe_twist;
  got["init_affine_min_change"] = o.init_affine_min_change;
  got["init_rotation_rates"] = o.init_rotation_rates;
  got["max_lost_frames"] = o.max_lost_frames;
  got["fail_max_rmse"] = o.fail_max_rmse;
  got["fail_min_inlier_ratio"] = o.fail_min_inlier_ratio;
  got["fail_min_points"] = o.fail_min_points;
  got["fail_max_scale_change"] = o.fail_max_scale_change;
  test::expectEveryKeyRead("backend", table, sec, got);
}

TEST(BackendOptions, ProblemsNameTheKey) {
  try {
    backendOptionsFromConfig(nlohmann::json{{"backend", {{"max_keyframez", 7}}}});
    FAIL() << "an unknown key must be rejected";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("max_keyframez"), std::string::npos) << e.what();
  }
  try {
    backendOptionsFromConfig(nlohmann::json{{"backend", {{"max_keyframes", "seven"}}}});
    FAIL() << "a wrong type must be rejected";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("max_keyframes"), std::string::npos) << e.what();
  }
  try {
    backendOptionsFromConfig(nlohmann::json{{"backend", {{"max_keyframes", 1}}}});
    FAIL() << "a value below the range must be rejected";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("max_keyframes"), std::string::npos) << e.what();
  }
}

TEST(BackendOptions, CrossFieldChecks) {
  try {
    backendOptionsFromConfig(nlohmann::json{{"backend", {{"min_keyframes", 8}, {"max_keyframes", 7}}}});
    FAIL() << "min_keyframes > max_keyframes must be rejected";
  } catch (const ConfigError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("backend.min_keyframes = 8"), std::string::npos) << m;
    EXPECT_NE(m.find("max_keyframes"), std::string::npos) << m;
  }
  try {
    backendOptionsFromConfig(nlohmann::json{{"backend", {{"init_min_frames", 60}, {"init_max_frames", 60}}}});
    FAIL() << "init_min_frames >= init_max_frames must be rejected";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("init_min_frames"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(backendOptionsFromConfig(nlohmann::json{{"backend", {{"min_keyframes", 7}, {"max_keyframes", 7}}}}));
}

}  // namespace
}  // namespace rsvio
