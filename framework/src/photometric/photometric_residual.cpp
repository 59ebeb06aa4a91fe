#include "rsvio/photometric/photometric_residual.h"

namespace rsvio {

bool makePatternHost(const ImageLevel& host, float u, float v, const ResidualOptions& opt, PatternHost* out) {
  const float c2 = static_cast<float>(opt.grad_weight_c * opt.grad_weight_c);
  float s[4];
  for (int i = 0; i < kPatternSize; ++i) {
    const float x = u + kPattern[i][0];
    const float y = v + kPattern[i][1];
    if (!host.inside(x, y, 1.f)) return false;
    host.sample(x, y, s);
    if (!std::isfinite(s[0])) return false;
    out->color[i] = s[0];
    out->weight[i] = gradientWeight(s[3], c2);
  }
  return true;
}

ParamTable ResidualOptions::paramTable() {
  const ResidualOptions d;
  return {
      paramDouble("residual_huber", d.huber_th, 0.1, 255.0, "intensity",
                  "Huber threshold of a photometric residual (DSO: 9)"),
      paramDouble("residual_grad_weight_c", d.grad_weight_c, 1.0, 1000.0, "intensity/px",
                  "c of the gradient weight c^2 / (c^2 + |grad|^2) (DSO: 50)"),
      paramDouble("residual_outlier_th", d.outlier_th, 1.0, 255.0, "intensity",
                  "an observation is an outlier when its energy exceeds 8 * th^2 (DSO: 12)"),
  };
}

ResidualOptions ResidualOptions::fromParams(const Params& p) {
  ResidualOptions o;
  o.huber_th = p.getDouble("residual_huber");
  o.grad_weight_c = p.getDouble("residual_grad_weight_c");
  o.outlier_th = p.getDouble("residual_outlier_th");
  return o;
}

}  // namespace rsvio
