// shutter.rolling: row v of the raw image is read at (v - y0) * line_delay after the image timestamp
// (top_down) or (y0 - v) * line_delay (bottom_up); y0 = (h - 1) / 2 (conventions.md, "Time").
//
// Calibration files rarely know the line delay (it is a hidden effect the user discovers), so the
// param line_delay_us wins over the calibration's line_delay_s; with neither positive the plugin
// refuses to start instead of running as a global shutter in disguise, unless estimate_line_delay
// asks the estimator to find it online (then that value, or 0, is where the estimate starts).
#include <cmath>
#include <memory>
#include <sstream>
#include <string>

#include "rsvio/core/error.h"
#include "rsvio/interfaces/shutter.h"
#include "rsvio/plugin/plugin_api.h"

namespace rsvio {
namespace {

const char* kName = "shutter.rolling";

ParamTable rollingParams();  // the parameter table, below

class RollingShutter : public ShutterModel {
 public:
  explicit RollingShutter(const Params& p)
      : param_line_delay_us_(p.getDouble("line_delay_us")),
        param_readout_(p.getString("readout")),
        estimate_(p.getBool("estimate_line_delay")) {}

  void setCalibration(const CameraCalibration& calib) override {
    double ld = param_line_delay_us_ > 0.0 ? param_line_delay_us_ * 1e-6 : calib.line_delay_s;
    if (estimate_ && !(ld > 0.0)) ld = 0.0;  // the estimate starts from 0
    if (!std::isfinite(ld) || (!estimate_ && !(ld > 0.0))) {
      std::string msg = std::string(kName) + " needs line_delay_us: the calibration has no line delay; give it with "
                        "--set shutter.params.line_delay_us=<microseconds per row> (readout time / image rows)";
      // When the plugin can estimate it, say so too (tests/apps/cli/newcomer_test.cpp holds this).
      for (const auto& spec : rollingParams())
        if (spec.key == "estimate_line_delay") msg += ", or estimate it with --set shutter.params.estimate_line_delay=true";
      throw ConfigError(msg);
    }
    const std::string readout = param_readout_ == "calibration" ? calib.readout : param_readout_;
    if (readout == "top_down") {
      sign_ = 1.0;
    } else if (readout == "bottom_up") {
      sign_ = -1.0;
    } else {
      throw ConfigError(std::string(kName) + ": calibration readout \"" + readout +
                        "\" is not supported (allowed: top_down, bottom_up)");
    }
    if (calib.height <= 0) {
      throw ConfigError(std::string(kName) + ": calibration image height must be positive");
    }
    y0_ = calib.rowZero();
    line_delay_s_ = ld;
    has_calib_ = true;
  }

  bool isRolling() const override { return true; }
  double rowTime(double v) const override {
    requireCalibration();
    return sign_ * line_delay_s_ * (v - y0_);
  }
  double rowTimeDerivative() const override {
    requireCalibration();
    return sign_ * line_delay_s_;  // -0.0 for a zero delay read bottom_up (shutter.h)
  }
  double lineDelay() const override { return line_delay_s_; }
  bool estimatesLineDelay() const override { return estimate_; }
  void setLineDelay(double line_delay_s) override {
    if (!(line_delay_s >= 0.0) || !std::isfinite(line_delay_s)) {
      std::ostringstream os;
      os << kName << ": setLineDelay(" << line_delay_s << "): the line delay must be finite and >= 0";
      throw Error(os.str());
    }
    line_delay_s_ = line_delay_s;
  }

 private:
  void requireCalibration() const {
    if (!has_calib_) throw Error(std::string(kName) + ": used before setCalibration()");
  }

  double param_line_delay_us_;
  std::string param_readout_;
  bool estimate_ = false;
  double y0_ = 0.0;
  double sign_ = 1.0;
  double line_delay_s_ = 0.0;
  bool has_calib_ = false;
};

ParamTable rollingParams() {
  return {paramDouble("line_delay_us", 0.0, 0.0, 1e5, "us",
                      "time between two consecutive rows; 0 = the calibration's line_delay_s"),
          paramEnum("readout", "calibration", {"calibration", "top_down", "bottom_up"},
                    "readout direction; calibration = the calibration's readout"),
          paramBool("estimate_line_delay", false,
                    "estimate the line delay online in the window, starting from line_delay_us (or the "
                    "calibration's, or 0); the estimate goes to states.csv and report.json")};
}

void registerAll(PluginRegistrar& r) {
  r.add<ShutterModel>({kName, PluginKind::Shutter, "1.0.0",
                       "Rolling shutter with a constant line delay, read top_down or bottom_up",
                       rollingParams(), ""},
                      [](const Params& p) { return std::make_unique<RollingShutter>(p); });
}

}  // namespace
}  // namespace rsvio

RSVIO_PLUGIN_ENTRY(rsvio::registerAll)
