// Interface of shutter.* plugins: when each raw row is read.
//
// Contract (conventions.md, "Time")
// - The image timestamp is the capture time of raw row y0 = (h - 1) / 2.
// - rowTime(v) is the capture time of raw row v RELATIVE to the image timestamp, in seconds:
//     global shutter:            0
//     rolling shutter top_down:  (v - y0) * line_delay_s
//     rolling shutter bottom_up: (y0 - v) * line_delay_s
//   so rowTimeDerivative() = d rowTime / d v is 0, +line_delay_s or -line_delay_s.
// - The pose at that time comes from the frame's twist (paper eq. 6): T_c_w(t) = exp(xi * t) * T_c_w^0,
//   xi per second. The rolling-shutter constraint v = project(T(t(v)) X).v is solved by the framework
//   (rsvio/geometry/rs_projection.h) using this interface; its Jacobians include d(row)/d(state).
// - A line delay the calibration does not know is a parameter of shutter.rolling (line_delay_us), or
//   estimated online (estimatesLineDelay(): the window optimises it from lineDelay() as its start,
//   which may be 0). rowTimeDerivative() keeps the readout's sign for a zero line delay (-0.0 when
//   bottom_up), so the direction is known before there is a delay (RowTiming::from).
#pragma once
#include "rsvio/core/types.h"
#include "rsvio/plugin/plugin.h"

namespace rsvio {

class ShutterModel : public PluginBase {
 public:
  static constexpr PluginKind kKind = PluginKind::Shutter;

  virtual void setCalibration(const CameraCalibration& calib) = 0;
  virtual bool isRolling() const = 0;
  virtual double rowTime(double v) const = 0;       // s, relative to the image timestamp
  virtual double rowTimeDerivative() const = 0;     // s per row
  virtual double lineDelay() const = 0;             // s, >= 0 (0 for global)
  virtual void setLineDelay(double line_delay_s) = 0;  // for estimation; no effect on a global shutter
  virtual bool estimatesLineDelay() const { return false; }  // the estimator should optimise it online
};

}  // namespace rsvio
