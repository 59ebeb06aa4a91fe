// Interface of effect.* plugins: physical effects of the simulator (`rsvio simulate`), each a switch.
//
// Contract
// - The simulator (framework/include/rsvio/sim/) calls the hooks in this order for every effect in the
//   config's "effects" object (sorted by order(), then name):
//     configure(): once, may change the sensor model (line delay, time offset, distortion, exposure).
//     processImage(): per image, on the linear irradiance image (CV_32F) before quantisation, in
//       image-pipeline order (vignetting -> exposure/gain -> noise -> response ...).
//     processImu(): once on the whole IMU stream (noise, biases).
// - Randomness only from the Rng handed in: one stream per (seed, effect name), so switching one effect
//   never changes another's noise (conventions.md, Determinism).
// - truth(): the effect's parameters for truth.json. inCalibration(): whether a calibration would know
//   it (distortion: yes; rolling shutter, time offset, vignetting, response, exposure: no).
// The simulator issue owns the details of SimContext; it may extend this header.
#pragma once
#include <nlohmann/json.hpp>
#include <random>
#include <vector>

#include "rsvio/core/types.h"
#include "rsvio/plugin/plugin.h"

namespace rsvio {

struct SimSensorModel;   // defined by the simulator (rsvio/sim/)
struct SimImageContext;  // defined by the simulator (rsvio/sim/)

class SimEffect : public PluginBase {
 public:
  static constexpr PluginKind kKind = PluginKind::Effect;

  virtual int order() const { return 100; }
  virtual void configure(SimSensorModel& /*sensor*/) {}
  virtual void processImage(cv::Mat& /*irradiance_f32*/, const SimImageContext& /*ctx*/, std::mt19937_64& /*rng*/) {}
  virtual void processImu(std::vector<ImuSample>& /*samples*/, std::mt19937_64& /*rng*/) {}
  virtual nlohmann::json truth() const = 0;
  virtual bool inCalibration() const { return false; }
};

}  // namespace rsvio
