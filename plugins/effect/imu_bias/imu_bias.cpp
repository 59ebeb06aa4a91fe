// effect.imu_bias: a constant bias on gyroscope and accelerometer, added to every sample and to the
// ground truth's b_w, b_a. Hidden: truth.json and the ground truth only (an estimator must find it).
#include <memory>

#include "rsvio/interfaces/sim_effect.h"
#include "rsvio/plugin/plugin_api.h"

namespace rsvio {
namespace {

ParamTable table() {
  return {paramArray("gyro_bias_rad_s", {0.003, -0.002, 0.004}, 3, "rad/s", "constant gyroscope bias, body frame"),
          paramArray("accel_bias_m_s2", {0.05, -0.08, 0.1}, 3, "m/s^2", "constant accelerometer bias, body frame")};
}

Vec3 toVec3(const std::vector<double>& v) { return Vec3(v[0], v[1], v[2]); }

class ImuBias : public SimEffect {
 public:
  explicit ImuBias(const Params& p)
      : bg_(toVec3(p.getArray("gyro_bias_rad_s"))), ba_(toVec3(p.getArray("accel_bias_m_s2"))) {}
  int order() const override { return 10; }
  void processImu(std::vector<ImuSample>& samples, SimImuContext& ctx, std::mt19937_64&) override {
    for (size_t k = 0; k < samples.size(); ++k) {
      samples[k].gyro_rad_s += bg_;
      samples[k].accel_m_s2 += ba_;
      ctx.gyro_bias_rad_s[k] += bg_;
      ctx.accel_bias_m_s2[k] += ba_;
    }
  }
  nlohmann::json truth() const override {
    return {{"gyro_bias_rad_s", {bg_.x(), bg_.y(), bg_.z()}}, {"accel_bias_m_s2", {ba_.x(), ba_.y(), ba_.z()}}};
  }

 private:
  Vec3 bg_, ba_;
};

void registerAll(PluginRegistrar& r) {
  r.add<SimEffect>({"effect.imu_bias", PluginKind::Effect, "1.0.0",
                    "constant gyroscope and accelerometer bias (hidden: truth.json and ground truth)", table()},
                   [](const Params& p) { return std::make_unique<ImuBias>(p); });
}

}  // namespace
}  // namespace rsvio

RSVIO_PLUGIN_ENTRY(rsvio::registerAll)
