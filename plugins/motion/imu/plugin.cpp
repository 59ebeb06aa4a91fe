// motion.imu: registration and parameter table (the model: imu_motion_prior.h).
#include <memory>

#include "imu_motion_prior.h"
#include "rsvio/plugin/plugin_api.h"

namespace rsvio {
namespace {

ParamTable table() {
  const ImuMotionOptions d;
  return {
      paramDouble("twist_sigma_trans_m_s", d.twist_sigma_trans_m_s, 1e-6, 100.0, "m/s",
                  "standard deviation of the IMU twist prior's translation (metric; eq. 33's Sigma)"),
      paramDouble("twist_sigma_rot_rad_s", d.twist_sigma_rot_rad_s, 1e-6, 10.0, "rad/s",
                  "standard deviation of the IMU twist prior's rotation (eq. 33's Sigma)"),
      paramDouble("buffer_s", d.buffer_s, 0.1, 3600.0, "s", "IMU history kept for predictions and twist priors"),
      paramDouble("max_extrapolation_ms", d.max_extrapolation_ms, 0.0, 100.0, "ms",
                  "a camera time this far past the last IMU sample uses that sample"),
      paramBool("recovery", d.recovery, "append the constant-velocity and no-motion guesses after the IMU's"),
      paramBool("gyro_rotation_guess", d.gyro_rotation_guess,
                "before the visual-inertial initialisation: the first guess's rotation from the gyroscope, its "
                "translation from constant velocity"),
      paramDouble("smooth_twist_info_trans", d.smooth_twist_info_trans, 0.0, 1e12, "s^2/unit^2",
                  "information of the window's smooth-motion prior on rolling-shutter twists, translation (0: none)"),
      paramDouble("smooth_twist_info_rot", d.smooth_twist_info_rot, 0.0, 1e12, "s^2/rad^2",
                  "information of the window's smooth-motion prior on rolling-shutter twists, rotation"),
  };
}

void registerAll(PluginRegistrar& r) {
  r.add<MotionPrior>({"motion.imu", PluginKind::Motion, "1.0.0",
                      "IMU-integrated pose guesses from the last state and the IMU twist prior (eqs. 22-33)", table(),
                      ""},
                     [](const Params& p) {
                       ImuMotionOptions o;
                       o.twist_sigma_trans_m_s = p.getDouble("twist_sigma_trans_m_s");
                       o.twist_sigma_rot_rad_s = p.getDouble("twist_sigma_rot_rad_s");
                       o.buffer_s = p.getDouble("buffer_s");
                       o.max_extrapolation_ms = p.getDouble("max_extrapolation_ms");
                       o.recovery = p.getBool("recovery");
                       o.gyro_rotation_guess = p.getBool("gyro_rotation_guess");
                       o.smooth_twist_info_trans = p.getDouble("smooth_twist_info_trans");
                       o.smooth_twist_info_rot = p.getDouble("smooth_twist_info_rot");
                       return std::make_unique<ImuMotionPrior>(o);
                     });
}

}  // namespace
}  // namespace rsvio

RSVIO_PLUGIN_ENTRY(rsvio::registerAll)
