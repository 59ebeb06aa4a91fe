// The simulator: effects, frames, IMU and ground truth (rsvio/sim/simulator.h). Files: simulator_write.cpp.
#include "rsvio/sim/simulator.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "rsvio/core/error.h"
#include "rsvio/plugin/host.h"
#include "rsvio/sim/rng.h"

namespace rsvio::sim {

namespace {

bool sameCalibration(const CameraCalibration& a, const CameraCalibration& b) {
  return a.width == b.width && a.height == b.height && a.intrinsics == b.intrinsics && a.distortion == b.distortion &&
         a.distortion_coeffs.size() == b.distortion_coeffs.size() &&
         (a.distortion_coeffs.size() == 0 || a.distortion_coeffs == b.distortion_coeffs) &&
         a.T_B_C.matrix() == b.T_B_C.matrix() && a.rate_hz == b.rate_hz && a.line_delay_s == b.line_delay_s &&
         a.time_offset_s == b.time_offset_s;
}

bool sameImuSpec(const ImuNoise& a, const ImuNoise& b) {
  return a.rate_hz == b.rate_hz && a.gyro_noise_density == b.gyro_noise_density &&
         a.gyro_random_walk == b.gyro_random_walk && a.accel_noise_density == b.accel_noise_density &&
         a.accel_random_walk == b.accel_random_walk;
}

std::string fmt(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

}  // namespace

Simulator::Simulator(const nlohmann::json& effective, PluginHost& host) : config_(effective) {
  settings_ = simSettings(effective);
  sensor_ = settings_.sensor;

  if (effective.contains("effects")) {
    for (const auto& [name, slot] : effective.at("effects").items()) {
      Effect e;
      e.name = name;
      e.plugin = slot.at("plugin").get<std::string>();
      e.params = slot.contains("params") ? slot.at("params") : nlohmann::json::object();
      e.impl = host.create<SimEffect>(e.plugin, Params(e.params, "effects." + name + ".params"), "effects." + name);
      effects_.push_back(std::move(e));
    }
  }
  std::stable_sort(effects_.begin(), effects_.end(), [](const Effect& a, const Effect& b) {
    return a.impl->order() != b.impl->order() ? a.impl->order() < b.impl->order() : a.name < b.name;
  });
  for (Effect& e : effects_) {
    const SimSensorModel before = sensor_;
    e.impl->configure(sensor_);
    // An effect a calibration would not know must not change what the calibration files say.
    if (!e.impl->inCalibration() && (!sameCalibration(before.camera, sensor_.camera) || !sameImuSpec(before.imu, sensor_.imu)))
      throw PluginError("effects." + e.name + " (" + e.plugin +
                        "): changed the calibration although it is a hidden effect (inCalibration() is false)");
    sensor_.camera.line_delay_s = 0.0;  // the calibration-visible part never holds hidden truth
    sensor_.camera.time_offset_s = 0.0;
  }
  const double margin = settings_.frame_margin_s;
  const double reach = std::abs(sensor_.time_offset_s) + 0.5 * sensor_.readoutTime() + 0.5 * sensor_.exposure_s;
  if (reach > margin + 1e-12)
    throw ConfigError("output.frame_margin_s: " + fmt(margin) + " s is shorter than |time offset| + readout / 2 + exposure / 2 = " +
                      fmt(reach) + " s of the effects; raise it so every row is captured inside the IMU stream");

  std::mt19937_64 rng = makeStream(settings_.seed, "trajectory");
  trajectory_ = SimTrajectory::generate(settings_.motion, rng);

  const double period = 1.0 / sensor_.camera.rate_hz;
  for (int64_t k = 0;; ++k) {
    const double t = margin + static_cast<double>(k) * period;
    if (t > settings_.motion.duration_s - margin + 1e-9) break;
    frame_stamps_.push_back(sensor_.start_ns + std::llround(t * 1e9));
  }
  synthesizeImu();
}

Simulator::~Simulator() = default;

void Simulator::synthesizeImu() {
  const std::vector<int64_t> stamps = streamStamps(sensor_.start_ns, settings_.motion.duration_s, sensor_.imu.rate_hz);
  imu_ = idealImu(trajectory_, stamps, sensor_.start_ns);
  SimImuContext ctx;
  ctx.rate_hz = sensor_.imu.rate_hz;
  ctx.sensor = &sensor_;
  ctx.gyro_bias_rad_s.assign(imu_.size(), Vec3::Zero());
  ctx.accel_bias_m_s2.assign(imu_.size(), Vec3::Zero());
  for (Effect& e : effects_) {
    std::mt19937_64 rng = makeStream(settings_.seed, "effect." + e.name);
    e.impl->processImu(imu_, ctx, rng);
    if (ctx.gyro_bias_rad_s.size() != imu_.size() || ctx.accel_bias_m_s2.size() != imu_.size())
      throw PluginError("effects." + e.name + " (" + e.plugin + "): resized the IMU bias tracks");
  }
  ground_truth_ = sim::groundTruth(trajectory_, stamps, sensor_.start_ns);
  for (size_t k = 0; k < ground_truth_.size(); ++k) {
    ground_truth_[k].gyro_bias = ctx.gyro_bias_rad_s[k];
    ground_truth_[k].accel_bias = ctx.accel_bias_m_s2[k];
  }
}

double Simulator::captureTime(size_t frame) const {
  return static_cast<double>(frame_stamps_.at(frame) - sensor_.start_ns) * 1e-9 + sensor_.time_offset_s;
}

void Simulator::prepareRendering() {
  std::call_once(render_once_, [this] {
    auto scene = std::make_unique<Scene>(Scene::defaultRoom(settings_.scene, settings_.seed, settings_.threads));
    auto renderer = std::make_unique<Renderer>(*scene, trajectory_, sensor_, settings_.supersampling);
    scene_ = std::move(scene);
    renderer_ = std::move(renderer);
  });
}

const Scene& Simulator::scene() {
  prepareRendering();
  return *scene_;
}

const Renderer& Simulator::renderer() {
  prepareRendering();
  return *renderer_;
}

cv::Mat Simulator::renderSignal(size_t frame, nlohmann::json* frame_truth) const {
  if (!renderer_) throw Error("Simulator::renderSignal: call prepareRendering() first");
  cv::Mat img = renderer_->render(captureTime(frame));
  SimImageContext ctx;
  ctx.index = static_cast<int64_t>(frame);
  ctx.t_cam_ns = frame_stamps_.at(frame);
  ctx.t_capture_s = captureTime(frame);
  ctx.sensor = &sensor_;
  for (const Effect& e : effects_) {
    nlohmann::json ft = nlohmann::json::object();
    ctx.frame_truth = &ft;
    std::mt19937_64 rng = makeStream(settings_.seed, "effect." + e.name, static_cast<uint64_t>(frame));
    e.impl->processImage(img, ctx, rng);
    if (img.type() != CV_32F || img.rows != sensor_.camera.height || img.cols != sensor_.camera.width)
      throw PluginError("effects." + e.name + " (" + e.plugin + "): changed the image's size or type");
    if (frame_truth && !ft.empty()) (*frame_truth)[e.name] = ft;
  }
  return img;
}

cv::Mat Simulator::quantize(const cv::Mat& signal) const {
  cv::Mat clipped = cv::max(cv::min(signal, 1.0), 0.0);
  cv::Mat out;
  const bool deep = sensor_.bit_depth == 16;
  clipped.convertTo(out, deep ? CV_16U : CV_8U, deep ? 65535.0 : 255.0);
  return out;
}

cv::Mat Simulator::renderImage(size_t frame, nlohmann::json* frame_truth) const {
  return quantize(renderSignal(frame, frame_truth));
}

std::vector<GroundTruthState> Simulator::mocap() const {
  return sim::groundTruth(trajectory_, streamStamps(sensor_.start_ns, settings_.motion.duration_s, settings_.mocap_rate_hz),
                     sensor_.start_ns);
}

MotionStats Simulator::motionStats() const { return trajectory_.stats(sensor_.imu.rate_hz); }

}  // namespace rsvio::sim
