// The simulator behind `rsvio simulate`: builds the world from an effective simulation config
// (sim_config.h), applies the effect plugins and writes the EuRoC/ASL dataset plus truth.json.
//
// Contract
// - Clocks (sensor_model.h): IMU and ground truth on the IMU clock; images stamped on the camera clock
//   at the capture time of row y0. Images are taken every 1 / camera.rate_hz from output.frame_margin_s
//   after the first IMU sample to frame_margin_s before the last one, whatever the effects, so a
//   global/rolling-shutter pair has the same stamps. The image stamped t_cam is captured at IMU time
//   t_cam + time_offset_s (Kalibr's sign, t_imu = t_cam + time_offset).
// - Random streams (rng.h): trajectory from (seed, "trajectory"), scene from (seed, "scene"), effects
//   from (seed, "effect.<member name>"[, frame]). So one seed gives the same trajectory, scene and noise
//   whatever effects are on.
// - Effects run sorted by (order(), name); configure() before anything is generated.
// - Deterministic: the dataset is identical, byte for byte, for any `threads`.
#pragma once
#include <functional>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "rsvio/interfaces/sim_effect.h"
#include "rsvio/sim/imu_synth.h"
#include "rsvio/sim/renderer.h"
#include "rsvio/sim/scene.h"
#include "rsvio/sim/sim_config.h"
#include "rsvio/sim/trajectory.h"

namespace rsvio {

class PluginHost;

namespace sim {

struct SimProgress {
  std::string stage;  // "scene", "imu", "frames", "done"
  int64_t done = 0, total = 0;
  double elapsed_s = 0.0;
};
using SimProgressFn = std::function<void(const SimProgress&)>;

class Simulator {
 public:
  // effective: a validated config (validateSimConfig / loadSimConfig). Loads the effects through host.
  Simulator(const nlohmann::json& effective, PluginHost& host);
  ~Simulator();
  Simulator(const Simulator&) = delete;
  Simulator& operator=(const Simulator&) = delete;

  const SimSettings& settings() const { return settings_; }
  const SimSensorModel& sensor() const { return sensor_; }  // after the effects' configure()
  const SimTrajectory& trajectory() const { return trajectory_; }
  const nlohmann::json& config() const { return config_; }

  // Images: stamps on the camera clock, capture time of row y0 on the IMU clock (s from the start).
  const std::vector<int64_t>& frameStamps() const { return frame_stamps_; }
  double captureTime(size_t frame) const;

  // Builds the scene and the renderer (the slow part) if not done yet.
  void prepareRendering();
  const Scene& scene();
  const Renderer& renderer();
  // The linear signal of a frame after every image effect, before clipping and quantisation (CV_32F).
  // Thread-safe after prepareRendering().
  cv::Mat renderSignal(size_t frame, nlohmann::json* frame_truth = nullptr) const;
  cv::Mat quantize(const cv::Mat& signal) const;  // CV_8U or CV_16U as sensor().bit_depth says
  cv::Mat renderImage(size_t frame, nlohmann::json* frame_truth = nullptr) const;

  // IMU samples with the effects applied, and the ground truth at the same stamps (true biases).
  const std::vector<ImuSample>& imu() const { return imu_; }
  const std::vector<GroundTruthState>& groundTruth() const { return ground_truth_; }
  std::vector<GroundTruthState> mocap() const;
  MotionStats motionStats() const;

  // truth.json's content; frames: per-frame truth collected while rendering (may be empty).
  nlohmann::json truth(const nlohmann::json& frames) const;
  // Writes the whole dataset into dir (created). Progress is reported from worker threads, serialised.
  void write(const std::string& dir, const SimProgressFn& progress = nullptr);

 private:
  struct Effect {
    std::string name, plugin;
    nlohmann::json params;
    std::unique_ptr<SimEffect> impl;
  };
  void synthesizeImu();

  nlohmann::json config_;
  SimSettings settings_;
  SimSensorModel sensor_;
  SimTrajectory trajectory_;
  std::vector<Effect> effects_;
  std::vector<int64_t> frame_stamps_;
  std::vector<ImuSample> imu_;
  std::vector<GroundTruthState> ground_truth_;
  std::unique_ptr<Scene> scene_;
  std::unique_ptr<Renderer> renderer_;
  std::once_flag render_once_;
};

}  // namespace sim
}  // namespace rsvio
