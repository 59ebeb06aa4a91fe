// The diagnosis of a run (rsvio diagnose, rsvio demo): every probe.* plugin on the run's folder alone
// (diagnostics.bin, config.json, report.json; never truth.json or ground truth), ranked.
#pragma once
#include <nlohmann/json.hpp>
#include <string>

namespace rsvio {
class PluginHost;
}

namespace rsvio::app {

struct DiagnoseRequest {
  std::string run_dir;
  std::string against;   // a run before the change ("" = none): error before/after, evidence gone?
  bool figures = true;   // PNGs into <run>/figures and a section in <run>/index.html
};

// The user contract's JSON (verdict, ranking with effect/score/plugin/config_line/statistic/threshold)
// plus data (how much the log held), not_applicable, figures and, with `against`, the comparison.
// Throws DataError naming the file when the run folder has no readable diagnostics log or config.
nlohmann::json diagnoseRun(const DiagnoseRequest& req, PluginHost& host);

// The terminal text of a diagnosis (a few lines).
std::string formatDiagnosis(const nlohmann::json& d);

}  // namespace rsvio::app
