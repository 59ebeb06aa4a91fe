// Interface of probe.* plugins: one diagnostic probe per physical effect, used by `rsvio diagnose`.
//
// Contract
// - evaluate() reads a finished run's diagnostics log (rsvio/io/diagnostics_log.h), its effective
//   config and, when they could be read, the run's trajectory and the dataset's measurements (IMU
//   samples, calibration; never ground truth or truth.json), and returns a statistic held against a
//   threshold: score = statistic / threshold, so a score above 1 means "this effect explains what the
//   model misses". A probe that needs an input that is missing says so (too little data, score 0).
// - A probe whose effect the run already models (e.g. shutter.rolling in use) returns applicable=false;
//   diagnose never names an effect the run models.
// - config_line is a literal `--set key=value` argument (or several) that can be pasted after `rsvio run`.
#pragma once
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "rsvio/core/types.h"
#include "rsvio/plugin/plugin.h"

namespace rsvio {

struct DiagnosticsLog;  // rsvio/io/diagnostics_log.h
namespace io {
struct Trajectory;      // rsvio/io/trajectory.h
}

// What a probe may read of a run. The pointers are null when the input is not available (a run that
// wrote no trajectory, a dataset that moved since the run).
struct ProbeInput {
  const DiagnosticsLog& log;
  const nlohmann::json& config;                  // the effective config the residuals are judged against
  // The config the run itself used, where it differs from `config` (diagnose --against judges a new
  // run as if the effect were unmodelled): what its outputs assumed, e.g. the clock of its stamps.
  const nlohmann::json* run_config = nullptr;
  const io::Trajectory* trajectory = nullptr;    // the run's trajectory.tum (every tracked frame)
  const SensorSetup* sensors = nullptr;          // the dataset's calibration (DataSource::sensors)
  const std::vector<ImuSample>* imu = nullptr;   // the dataset's IMU samples, IMU clock
};

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
  virtual ProbeResult evaluate(const ProbeInput& in) const = 0;
};

}  // namespace rsvio
