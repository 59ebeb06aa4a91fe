// Helpers of the simulator tests: a plugin host on the build's plugin folder and tiny configs.
#pragma once
#include <gtest/gtest.h>

#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "rsvio/config/config.h"
#include "rsvio/plugin/host.h"
#include "rsvio/sim/sim_config.h"
#include "rsvio/sim/simulator.h"

namespace rsvio::sim::test {

inline PluginHost& host() {
  static PluginHost h({RSVIO_PLUGIN_DIR});
  return h;
}

inline std::string simConfigPath(const std::string& name) {
  return std::string(RSVIO_SOURCE_DIR) + "/configs/sim/" + name + ".json";
}

// A tiny config (configs/sim/<name>.json) with --set style overrides, validated.
inline nlohmann::json tinyConfig(const std::string& name, const std::vector<std::string>& sets = {}) {
  return loadSimConfig(simConfigPath(name), sets, std::nullopt, host());
}

// The same, with its effects replaced by `effects` (a JSON object; {} = no effect at all).
inline nlohmann::json withEffects(const std::string& name, const nlohmann::json& effects,
                                  const std::vector<std::string>& sets = {}) {
  nlohmann::json c = loadConfigWithSets(simConfigPath(name), sets);
  c["effects"] = effects;
  return validateSimConfig(c, host(), name);
}

inline nlohmann::json effect(const std::string& plugin, const nlohmann::json& params = nlohmann::json::object()) {
  return {{"plugin", plugin}, {"params", params}};
}

}  // namespace rsvio::sim::test
