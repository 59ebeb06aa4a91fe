// effect.imu_noise: white noise and bias random walk of gyroscope and accelerometer, the continuous
// model of Kalibr/EuRoC discretised at the IMU rate:
//     sample k:  m_k = ideal_k + b_k + sigma_d n_k,    sigma_d = noise_density * sqrt(rate)
//     bias:      b_{k+1} = b_k + random_walk * sqrt(1 / rate) w_k,    b_0 = 0
// with the densities of the config's "imu" section (what sensor.yaml states) times density_scale.
// On by default. A calibration knows the densities (in_calibration); a density_scale other than 1 makes
// sensor.yaml wrong on purpose. The bias walk is added to the ground truth's b_w, b_a.
#include <cmath>
#include <memory>

#include "rsvio/interfaces/sim_effect.h"
#include "rsvio/plugin/plugin_api.h"
#include "rsvio/sim/rng.h"

namespace rsvio {
namespace {

ParamTable table() {
  return {paramBool("white_noise", true, "add white measurement noise"),
          paramBool("bias_random_walk", true, "add a random-walk bias"),
          paramDouble("density_scale", 1.0, 0.0, 1000.0, "", "true noise / the imu section's (sensor.yaml) densities")};
}

class ImuNoiseEffect : public SimEffect {
 public:
  explicit ImuNoiseEffect(const Params& p)
      : white_(p.getBool("white_noise")), walk_(p.getBool("bias_random_walk")), scale_(p.getDouble("density_scale")) {}
  int order() const override { return 20; }
  bool inCalibration() const override { return true; }
  void configure(SimSensorModel& s) override { spec_ = s.imu; }
  void processImu(std::vector<ImuSample>& samples, SimImuContext& ctx, std::mt19937_64& rng) override {
    const double sq_rate = std::sqrt(ctx.rate_hz), sq_dt = std::sqrt(1.0 / ctx.rate_hz);
    const double sg = scale_ * spec_.gyro_noise_density * sq_rate, sa = scale_ * spec_.accel_noise_density * sq_rate;
    const double wg = scale_ * spec_.gyro_random_walk * sq_dt, wa = scale_ * spec_.accel_random_walk * sq_dt;
    Vec3 bg = Vec3::Zero(), ba = Vec3::Zero();
    for (size_t k = 0; k < samples.size(); ++k) {
      // Every number is drawn whatever the switches, so the stream's use never shifts.
      Vec3 ng, na, dg, da;
      for (int i = 0; i < 3; ++i) ng[i] = sim::gauss(rng);
      for (int i = 0; i < 3; ++i) na[i] = sim::gauss(rng);
      for (int i = 0; i < 3; ++i) dg[i] = sim::gauss(rng);
      for (int i = 0; i < 3; ++i) da[i] = sim::gauss(rng);
      samples[k].gyro_rad_s += bg + (white_ ? sg : 0.0) * ng;
      samples[k].accel_m_s2 += ba + (white_ ? sa : 0.0) * na;
      ctx.gyro_bias_rad_s[k] += bg;
      ctx.accel_bias_m_s2[k] += ba;
      if (walk_) {
        bg += wg * dg;
        ba += wa * da;
      }
    }
    final_bg_ = bg;
    final_ba_ = ba;
  }
  nlohmann::json truth() const override {
    return {{"model", "m_k = ideal_k + b_k + density * sqrt(rate) * n_k; b_{k+1} = b_k + random_walk * sqrt(dt) * w_k; b_0 = 0"},
            {"white_noise", white_},
            {"bias_random_walk", walk_},
            {"density_scale", scale_},
            {"gyroscope_noise_density", scale_ * spec_.gyro_noise_density},
            {"gyroscope_random_walk", scale_ * spec_.gyro_random_walk},
            {"accelerometer_noise_density", scale_ * spec_.accel_noise_density},
            {"accelerometer_random_walk", scale_ * spec_.accel_random_walk},
            {"final_walk_gyro_rad_s", {final_bg_.x(), final_bg_.y(), final_bg_.z()}},
            {"final_walk_accel_m_s2", {final_ba_.x(), final_ba_.y(), final_ba_.z()}}};
  }

 private:
  bool white_, walk_;
  double scale_;
  ImuNoise spec_;
  Vec3 final_bg_ = Vec3::Zero(), final_ba_ = Vec3::Zero();
};

void registerAll(PluginRegistrar& r) {
  r.add<SimEffect>({"effect.imu_noise", PluginKind::Effect, "1.0.0",
                    "IMU white noise and bias random walk from the imu section's densities (on by default)", table()},
                   [](const Params& p) { return std::make_unique<ImuNoiseEffect>(p); });
}

}  // namespace
}  // namespace rsvio

RSVIO_PLUGIN_ENTRY(rsvio::registerAll)
