// The "imu" section of a run config (rsvio/imu/inertial_options.h): every key of inertialParamTable()
// reaches InertialOptions, the table's defaults are the struct's, and a misspelt key is named.
#include <gtest/gtest.h>

#include <string>

#include "rsvio/core/error.h"
#include "rsvio/imu/inertial_options.h"
#include "support/param_table_check.h"

namespace rsvio {
namespace {

TEST(InertialOptions, EveryTableKeyIsRead) {
  const ParamTable table = inertialParamTable();
  ASSERT_GE(table.size(), 26u);
  const nlohmann::json sec = test::nonDefaultSection(table);
  const InertialOptions o = inertialOptionsFromConfig(nlohmann::json{{"imu", sec}});
  nlohmann::json got;
  got["enabled"] = o.enabled;
  got["imu_weight"] = o.imu_weight;
  got["twist_weight"] = o.twist_weight;
  got["estimate_time_offset"] = o.estimate_time_offset;
  got["time_offset_correction_ms"] = o.time_offset_correction_ms;
  got["init_time_offset_search_ms"] = o.init_time_offset_search_ms;
  got["frame_twist_from_imu"] = o.frame_twist_from_imu;
  got["smooth_motion_weight"] = o.smooth_motion_weight;
  got["gyro_bias_sigma_before_init_rad_s"] = o.gyro_bias_sigma_before_init_rad_s;
  got["frame_rotation_from_gyro_before_init"] = o.frame_rotation_from_gyro_before_init;
  got["init_rates_from_gyro"] = o.init_rates_from_gyro;
  got["init_track_guess_from_gyro"] = o.init_track_guess_from_gyro;
  got["readout_angular_acceleration"] = o.readout_angular_acceleration;
  got["twist_gyro_sigma_before_init_rad_s"] = o.twist_gyro_sigma_before_init_rad_s;
  got["smooth_motion_rot_weight_before_init"] = o.smooth_motion_rot_weight_before_init;
  got["init_min_keyframes"] = o.init_min_keyframes;
  got["init_min_duration_s"] = o.init_min_duration_s;
  got["init_min_accel_excitation_m_s2"] = o.init_min_accel_excitation_m_s2;
  got["init_max_gravity_norm_error"] = o.init_max_gravity_norm_error;
  got["accel_bias_prior_sigma_m_s2"] = o.accel_bias_prior_sigma_m_s2;
  got["init_max_gyro_bias_rad_s"] = o.init_max_gyro_bias_rad_s;
  got["init_max_accel_bias_m_s2"] = o.init_max_accel_bias_m_s2;
  got["init_min_interval_s"] = o.init_min_interval_s;
  got["init_max_imu_chi2"] = o.init_max_imu_chi2;
  got["init_refusals_warn"] = o.init_refusals_warn;
  got["init_restart_refusals"] = o.init_restart_refusals;
  got["init_max_restarts"] = o.init_max_restarts;
  got["init_restart_within_s"] = o.init_restart_within_s;
  got["dynamic_marginalization"] = o.dynamic_marginalization;
  got["dynamic_marginalization_interval"] = o.dynamic_marginalization_interval;
  got["init_scale_factor"] = o.init_scale_factor;
  got["repreintegrate_gyro_bias_rad_s"] = o.repreintegrate_gyro_bias_rad_s;
  got["repreintegrate_accel_bias_m_s2"] = o.repreintegrate_accel_bias_m_s2;
  got["fail_max_gyro_bias_rad_s"] = o.fail_max_gyro_bias_rad_s;
  got["fail_max_accel_bias_m_s2"] = o.fail_max_accel_bias_m_s2;
  got["fail_max_scale_change"] = o.fail_max_scale_change;
  got["fail_max_imu_chi2"] = o.fail_max_imu_chi2;
  got["fail_grace_s"] = o.fail_grace_s;
  got["fail_sustained_imu_chi2"] = o.fail_sustained_imu_chi2;
  got["fail_sustained_factor"] = o.fail_sustained_factor;
  got["fail_sustained_s"] = o.fail_sustained_s;
  got["warn_imu_chi2"] = o.warn_imu_chi2;
  test::expectEveryKeyRead("imu", table, sec, got);
}

TEST(InertialOptions, TheTablesDefaultsAreTheStructs) {
  const InertialOptions o = inertialOptionsFromConfig(nlohmann::json::object());
  const InertialOptions d;
  EXPECT_EQ(o.enabled, d.enabled);
  EXPECT_EQ(o.frame_twist_from_imu, d.frame_twist_from_imu);
  EXPECT_DOUBLE_EQ(o.smooth_motion_weight, d.smooth_motion_weight);
  EXPECT_DOUBLE_EQ(o.gyro_bias_sigma_before_init_rad_s, d.gyro_bias_sigma_before_init_rad_s);
  EXPECT_DOUBLE_EQ(o.init_max_imu_chi2, d.init_max_imu_chi2);
  EXPECT_DOUBLE_EQ(o.dynamic_marginalization_interval, d.dynamic_marginalization_interval);
  EXPECT_DOUBLE_EQ(o.fail_grace_s, d.fail_grace_s);
  EXPECT_DOUBLE_EQ(o.fail_sustained_imu_chi2, d.fail_sustained_imu_chi2);
  EXPECT_DOUBLE_EQ(o.fail_sustained_factor, d.fail_sustained_factor);
  EXPECT_DOUBLE_EQ(o.fail_sustained_s, d.fail_sustained_s);
  EXPECT_DOUBLE_EQ(o.warn_imu_chi2, d.warn_imu_chi2);
}

TEST(InertialOptions, AMisspeltKeyIsNamed) {
  try {
    inertialOptionsFromConfig(nlohmann::json{{"imu", {{"smooth_motion_wieght", 0.5}}}});
    FAIL() << "an unknown key must be rejected";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("smooth_motion_wieght"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace rsvio
