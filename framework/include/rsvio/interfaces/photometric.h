// Interface of photometric.* plugins: the image-formation model between scene radiance and pixel value.
//
// Contract (DSO's model, Engel et al. 2018, section 2.1)
//   I(x) = G(t * V(x) * B(x))    G: response, V: vignetting, t: exposure, B: irradiance
// and per-frame affine brightness (a, b), with the residual of a host pixel i seen in target j
//   r = (I_j[p'] - b_j) - exp(a_j - a_i) * (I_i[p] - b_i).
// - correct(): applied to every image in slot order before the pyramid is built; turns raw values into
//   the model's working domain (e.g. inverse response, then divide by the vignette). Images are CV_32F
//   scaled so that 0..255 spans the raw range whatever the bit depth.
// - hasAffineBrightness(): this model adds (a, b) per frame to the optimisation; the priors say how
//   strongly a and b are pulled to 0 (DSO's affine priors; 0 = free).
// - Models with parameters expose them through numParams/params/setParams and may predict the
//   target-side value with its derivatives in predict() (the default is the identity; the back end does
//   not call predict()).
// - Online estimation by alternation (estimatesOnline(), e.g. photometric.vignette without a
//   calibration): correct() applies the current parameters, and after each keyframe the back end hands
//   refineFromResiduals() the observations that left the window (io/diagnostics_log.h rows, outliers
//   with weight 0) whose host and target images were both corrected with them, once there are at least
//   minRowsForRefine(). It returns true when the parameters changed; the frames after that keyframe are
//   corrected with the new ones, and the rows before are not handed over again.
#pragma once
#include <Eigen/Core>

#include <string>
#include <vector>

#include "rsvio/core/types.h"
#include "rsvio/io/diagnostics_log.h"
#include "rsvio/plugin/plugin.h"

namespace rsvio {

class PhotometricModel : public PluginBase {
 public:
  static constexpr PluginKind kKind = PluginKind::Photometric;

  virtual void setSensors(const SensorSetup& /*sensors*/) {}
  virtual void correct(cv::Mat& /*image_f32*/, const Frame& /*frame*/) const {}

  virtual bool hasAffineBrightness() const { return false; }
  virtual double affinePriorA() const { return 0.0; }
  virtual double affinePriorB() const { return 0.0; }

  virtual int numParams() const { return 0; }
  virtual Eigen::VectorXd params() const { return Eigen::VectorXd(); }
  virtual void setParams(const Eigen::VectorXd& /*p*/) {}
  // Online estimation by alternation (above). `note`: one line saying what changed (report.json keeps it).
  virtual bool estimatesOnline() const { return false; }
  virtual size_t minRowsForRefine() const { return 0; }
  virtual bool refineFromResiduals(const std::vector<ObservationRow>& /*rows*/, std::string* /*note*/) { return false; }
  // Predicted working-domain value at raw pixel uv of a scene value `value`; d_value = d out / d value,
  // d_params (size numParams()) = d out / d params when non-null.
  virtual double predict(double value, const Vec2& /*uv*/, double* d_value, Eigen::VectorXd* d_params) const {
    if (d_value) *d_value = 1.0;
    if (d_params) d_params->resize(0);
    return value;
  }
};

}  // namespace rsvio
