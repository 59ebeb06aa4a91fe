// effect.image_noise: sensor noise on the linear signal x (1 = full scale): shot noise with
// variance x / full_well_e (photon counting) plus read noise of read_noise_dn / 255 (in 8-bit digital
// numbers), Gaussian, independent per pixel. Applied before the response curve and quantisation.
// On by default. Noise from the stream (seed, "effect.<name>", frame), so it does not depend on other
// effects or on threads.
#include <cmath>
#include <memory>

#include "rsvio/interfaces/sim_effect.h"
#include "rsvio/plugin/plugin_api.h"
#include "rsvio/sim/rng.h"

namespace rsvio {
namespace {

ParamTable table() {
  return {paramDouble("read_noise_dn", 0.8, 0.0, 255.0, "DN", "read noise standard deviation in 8-bit digital numbers"),
          paramDouble("full_well_e", 6000.0, 0.0, 1e7, "e-", "electrons at full scale, for shot noise (0: no shot noise)")};
}

class ImageNoise : public SimEffect {
 public:
  explicit ImageNoise(const Params& p) : read_(p.getDouble("read_noise_dn") / 255.0), full_well_(p.getDouble("full_well_e")) {}
  int order() const override { return 30; }
  void processImage(cv::Mat& signal, const SimImageContext&, std::mt19937_64& rng) const override {
    const double read2 = read_ * read_;
    for (int y = 0; y < signal.rows; ++y) {
      float* row = signal.ptr<float>(y);
      for (int x = 0; x < signal.cols; ++x) {
        const double v = row[x];
        const double var = read2 + (full_well_ > 0 ? std::max(v, 0.0) / full_well_ : 0.0);
        row[x] = static_cast<float>(v + std::sqrt(var) * sim::gauss(rng));  // always one draw per pixel
      }
    }
  }
  nlohmann::json truth() const override {
    return {{"model", "x + n, n ~ N(0, (read_noise_dn / 255)^2 + x / full_well_e), x the linear signal (1 = full scale)"},
            {"read_noise_dn", read_ * 255.0},
            {"full_well_e", full_well_}};
  }

 private:
  double read_, full_well_;
};

void registerAll(PluginRegistrar& r) {
  r.add<SimEffect>({"effect.image_noise", PluginKind::Effect, "1.0.0",
                    "shot and read noise of the image sensor (on by default)", table()},
                   [](const Params& p) { return std::make_unique<ImageNoise>(p); });
}

}  // namespace
}  // namespace rsvio

RSVIO_PLUGIN_ENTRY(rsvio::registerAll)
