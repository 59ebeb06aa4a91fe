// effect.time_offset: the camera clock runs `offset_ms` behind the IMU clock (Kalibr's sign,
// t_imu = t_cam + time_offset). How it shows in the files: cam0/data.csv keeps its regular stamps on
// the camera clock, imu0 and the ground truth keep theirs on the IMU clock, and the image stamped
// t_cam shows the world at IMU time t_cam + offset. So an estimator that takes the stamps at face
// value sees images offset_ms late (positive offset) against the IMU. Hidden: truth.json only.
#include <memory>

#include "rsvio/interfaces/sim_effect.h"
#include "rsvio/plugin/plugin_api.h"

namespace rsvio {
namespace {

ParamTable table() {
  return {paramDouble("offset_ms", 5.0, -100.0, 100.0, "ms",
                      "t_imu - t_cam (Kalibr's sign): the image stamped t_cam is captured at IMU time t_cam + offset")};
}

class TimeOffset : public SimEffect {
 public:
  explicit TimeOffset(const Params& p) : offset_s_(p.getDouble("offset_ms") * 1e-3) {}
  int order() const override { return 10; }
  void configure(SimSensorModel& s) override { s.time_offset_s = offset_s_; }
  nlohmann::json truth() const override {
    return {{"time_offset_s", offset_s_},
            {"rule", "t_imu = t_cam + time_offset_s: cam0 stamps are on the camera clock; the image stamped t_cam "
                     "shows the world at IMU/ground-truth time t_cam + time_offset_s"}};
  }

 private:
  double offset_s_;
};

void registerAll(PluginRegistrar& r) {
  r.add<SimEffect>({"effect.time_offset", PluginKind::Effect, "1.0.0",
                    "camera-IMU time offset, t_imu = t_cam + offset (hidden: truth.json only)", table()},
                   [](const Params& p) { return std::make_unique<TimeOffset>(p); });
}

}  // namespace
}  // namespace rsvio

RSVIO_PLUGIN_ENTRY(rsvio::registerAll)
