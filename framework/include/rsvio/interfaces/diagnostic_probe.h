// Interface of probe.* plugins: one diagnostic probe per physical effect, used by `rsvio diagnose`.
//
// Contract
// - evaluate() reads a finished run's diagnostics log (rsvio/io/diagnostics_log.h) and its effective
//   config, and returns a statistic held against a threshold: score = statistic / threshold, so a
//   score above 1 means "this effect explains what the model misses".
// - A probe whose effect the run already models (e.g. shutter.rolling in use) returns applicable=false;
//   diagnose never names an effect the run models.
// - config_line is a literal `--set key=value` argument (or several) that can be pasted after `rsvio run`.
#pragma once
#include <nlohmann/json.hpp>
#include <string>

#include "rsvio/plugin/plugin.h"

namespace rsvio {

struct DiagnosticsLog;  // rsvio/io/diagnostics_log.h

struct ProbeResult {
  std::string effect;          // "rolling_shutter", "time_offset", "exposure", "vignetting", "response", "distortion"
  bool applicable = true;
  double statistic = 0.0;
  double threshold = 1.0;
  double score = 0.0;          // statistic / threshold
  std::string plugin;          // "shutter.rolling"
  std::string config_line;     // "--set shutter.plugin=shutter.rolling"
  std::string explanation;     // one line for the terminal
  nlohmann::json details;      // figures for the report
};

class DiagnosticProbe : public PluginBase {
 public:
  static constexpr PluginKind kKind = PluginKind::Probe;
  virtual std::string effect() const = 0;
  virtual ProbeResult evaluate(const DiagnosticsLog& log, const nlohmann::json& run_config) const = 0;
};

}  // namespace rsvio
