// effect.response: a non-linear camera response G applied to the linear signal x in [0, 1] after noise,
// before quantisation: value = G(clip(x)).
//   gamma:   G(x) = x^(1 / gamma)
//   s_curve: G(x) = x^c / (x^c + (1 - x)^c), c = contrast (film-like toe and shoulder)
// Hidden: truth.json only, with the inverse response as a 256-entry table in DSO's pcalib convention
// (pixel value i -> irradiance in [0, 255]).
#include <cmath>
#include <memory>

#include "rsvio/interfaces/sim_effect.h"
#include "rsvio/plugin/plugin_api.h"

namespace rsvio {
namespace {

ParamTable table() {
  return {paramEnum("model", "gamma", {"gamma", "s_curve"}, "shape of the response curve"),
          paramDouble("gamma", 2.2, 0.1, 10.0, "", "exponent of the gamma model: G(x) = x^(1/gamma)"),
          paramDouble("contrast", 1.6, 0.2, 10.0, "", "steepness c of the s_curve model")};
}

class Response : public SimEffect {
 public:
  explicit Response(const Params& p)
      : s_curve_(p.getString("model") == "s_curve"), gamma_(p.getDouble("gamma")), contrast_(p.getDouble("contrast")) {}
  int order() const override { return 40; }
  double G(double x) const {
    x = std::clamp(x, 0.0, 1.0);
    if (!s_curve_) return std::pow(x, 1.0 / gamma_);
    const double a = std::pow(x, contrast_), b = std::pow(1.0 - x, contrast_);
    return a / (a + b);
  }
  double Ginv(double v) const {
    v = std::clamp(v, 0.0, 1.0);
    if (!s_curve_) return std::pow(v, gamma_);
    if (v >= 1.0) return 1.0;
    const double q = std::pow(v / (1.0 - v), 1.0 / contrast_);
    return q / (1.0 + q);
  }
  void processImage(cv::Mat& signal, const SimImageContext&, std::mt19937_64&) const override {
    for (int y = 0; y < signal.rows; ++y) {
      float* row = signal.ptr<float>(y);
      for (int x = 0; x < signal.cols; ++x) row[x] = static_cast<float>(G(row[x]));
    }
  }
  nlohmann::json truth() const override {
    std::vector<double> inv(256);
    for (int i = 0; i < 256; ++i) inv[i] = 255.0 * Ginv(i / 255.0);
    nlohmann::json t = {{"model", s_curve_ ? "s_curve: G(x) = x^c / (x^c + (1 - x)^c)" : "gamma: G(x) = x^(1/gamma)"},
                        {"inverse_response_8bit", inv}};
    if (s_curve_) {
      t["contrast"] = contrast_;
    } else {
      t["gamma"] = gamma_;
    }
    return t;
  }

 private:
  bool s_curve_;
  double gamma_, contrast_;
};

void registerAll(PluginRegistrar& r) {
  r.add<SimEffect>({"effect.response", PluginKind::Effect, "1.0.0",
                    "non-linear camera response curve, gamma or s-curve (hidden)", table()},
                   [](const Params& p) { return std::make_unique<Response>(p); });
}

}  // namespace
}  // namespace rsvio

RSVIO_PLUGIN_ENTRY(rsvio::registerAll)
