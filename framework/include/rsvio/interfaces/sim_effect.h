// Interface of effect.* plugins: physical effects of the simulator (`rsvio simulate`), each a switch.
//
// Contract
// - The simulator (framework/include/rsvio/sim/) calls the hooks in this order for every effect in the
//   config's "effects" object (sorted by order(), then name):
//     configure(): once, before anything is generated; may change the sensor model (line delay,
//       readout, time offset, distortion, exposure window, IMU noise spec). Frames and units are those
//       of rsvio/sim/sensor_model.h.
//     processImage(): per image, on the linear sensor signal (CV_32F, 1.0 = full scale) before
//       clipping and quantisation, in image-pipeline order (vignetting -> exposure/gain -> noise ->
//       response). It is called concurrently for different frames from several threads: it must not
//       modify the effect's members (per-frame truth goes to ctx.frame_truth).
//     processImu(): once on the whole IMU stream (IMU clock); an effect that adds a bias also adds it
//       to ctx's bias tracks, which become the ground truth's biases.
// - Randomness only from the Rng handed in. processImage gets the stream (seed, "effect.<name>",
//   frame index); processImu the stream (seed, "effect.<name>"). So switching one effect never changes
//   another's noise, and a frame's noise is independent of threads (conventions.md, Determinism).
// - truth(): the effect's parameters for truth.json. inCalibration(): whether a calibration would know
//   it (distortion, IMU noise densities: yes; rolling shutter, time offset, vignetting, response,
//   exposure, IMU bias: no). Only effects with inCalibration() may change what sensor.yaml states.
#pragma once
#include <nlohmann/json.hpp>
#include <random>
#include <vector>

#include "rsvio/core/types.h"
#include "rsvio/plugin/plugin.h"
#include "rsvio/sim/sensor_model.h"

namespace rsvio {

class SimEffect : public PluginBase {
 public:
  static constexpr PluginKind kKind = PluginKind::Effect;

  virtual int order() const { return 100; }
  virtual void configure(SimSensorModel& /*sensor*/) {}
  virtual void processImage(cv::Mat& /*signal_f32*/, const SimImageContext& /*ctx*/, std::mt19937_64& /*rng*/) const {}
  virtual void processImu(std::vector<ImuSample>& /*samples*/, SimImuContext& /*ctx*/, std::mt19937_64& /*rng*/) {}
  virtual nlohmann::json truth() const = 0;
  virtual bool inCalibration() const { return false; }
};

}  // namespace rsvio
