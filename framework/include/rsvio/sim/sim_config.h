// Simulation configs (`rsvio simulate --config configs/sim/<name>.json`): schema, loading, settings.
//
//   { "extends": "gs.json",
//     "seed": 1, "threads": 2,
//     "scene":  {"room_size_m": [9, 7, 3], "furniture": 16, "texel_mm": 4, ...},
//     "camera": {"width_px": 640, "height_px": 512, "fx_px": 416, ..., "bit_depth": 8},
//     "motion": {"duration_s": 20, "mean_speed_m_s": 0.9, "mean_rot_speed_deg_s": 75, ...},
//     "imu":    {"rate_hz": 200, "gyroscope_noise_density": 1.7e-4, ...},
//     "output": {"start_time_ns": ..., "mocap_rate_hz": 120, ...},
//     "effects": {"rolling_shutter": {"plugin": "effect.rolling_shutter", "params": {"line_delay_us": 58.94}},
//                 "image_noise": {"plugin": "effect.image_noise"}, ...} }
//
// Validation is the framework's (config/validate.h): every problem at once, each with its JSON path and
// a did-you-mean; effect params are checked against each plugin's own table. Cross-field rules
// (principal point inside the image, heights inside the room, ...) follow in simSettings(), again
// naming the keys. A config without an "effects" key gets the defaults: image noise and IMU noise.
#pragma once
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "rsvio/config/validate.h"
#include "rsvio/sim/scene.h"
#include "rsvio/sim/sensor_model.h"
#include "rsvio/sim/trajectory.h"

namespace rsvio {

class PluginHost;

namespace sim {

// The schema of simulation configs.
ConfigSchema simConfigSchema();

// The effects a config without an "effects" key gets.
nlohmann::json defaultEffects();

// Loads a config file (extends, --set lines, --seed), fills default effects, validates it.
// Returns the effective config. Throws ConfigError naming file and JSON paths.
nlohmann::json loadSimConfig(const std::string& path, const std::vector<std::string>& sets,
                             std::optional<int64_t> seed, PluginHost& host);
// The same for a config already in memory (origin names it in messages).
nlohmann::json validateSimConfig(nlohmann::json config, PluginHost& host, const std::string& origin,
                                 const std::vector<std::string>& sets = {});  // sets: blamed for their problems

// Everything but the effects, from an effective config, with cross-field checks.
struct SimSettings {
  std::string name, description;
  uint64_t seed = 1;
  int threads = 2;
  SceneSpec scene;
  MotionSpec motion;
  SimSensorModel sensor;  // before effects' configure(): global shutter, no distortion, no offset
  int supersampling = 2;
  double mocap_rate_hz = 120.0;
  double frame_margin_s = 0.1;  // first/last image this far from the ends of the IMU stream
  int png_compression = 1;
  bool write_images = true;
};
SimSettings simSettings(const nlohmann::json& effective);

}  // namespace sim
}  // namespace rsvio
