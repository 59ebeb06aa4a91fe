// motion.constant_velocity: registration and parameter table (the model: constant_velocity.h).
#include <memory>

#include "constant_velocity.h"
#include "rsvio/plugin/plugin_api.h"

namespace rsvio {
namespace {

ParamTable table() {
  const ConstantVelocityOptions d;
  return {
      paramBool("recovery", d.recovery,
                "add DSO's recovery guesses: double/half/no motion, last keyframe, 26 small rotations"),
      paramDouble("recovery_rotation_rad", d.recovery_rotation_rad, 0.0, 0.5, "rad",
                  "angle of the rotated recovery guesses about each camera axis combination"),
      paramDouble("twist_info_trans", d.twist_info_trans, 0.0, 1e12, "s^2/unit^2",
                  "information of the smooth-motion twist prior, translation (0: no prior)"),
      paramDouble("twist_info_rot", d.twist_info_rot, 0.0, 1e12, "s^2/rad^2",
                  "information of the smooth-motion twist prior, rotation (0: no prior)"),
      paramEnum("twist_prior", "window", {"window", "history"},
                "rolling shutter: window = twist tied to the optimised neighbour keyframe poses; history = "
                "fixed mean from the tracked frame-to-frame velocity"),
  };
}

void registerAll(PluginRegistrar& r) {
  r.add<MotionPrior>({"motion.constant_velocity", PluginKind::Motion, "1.0.0",
                      "Constant-velocity guesses from the last two frames with DSO's recovery guesses", table(), ""},
                     [](const Params& p) {
                       ConstantVelocityOptions o;
                       o.recovery = p.getBool("recovery");
                       o.recovery_rotation_rad = p.getDouble("recovery_rotation_rad");
                       o.twist_info_trans = p.getDouble("twist_info_trans");
                       o.twist_info_rot = p.getDouble("twist_info_rot");
                       o.twist_prior_in_window = p.getString("twist_prior") == "window";
                       return std::make_unique<ConstantVelocityPrior>(o);
                     });
}

}  // namespace
}  // namespace rsvio

RSVIO_PLUGIN_ENTRY(rsvio::registerAll)
