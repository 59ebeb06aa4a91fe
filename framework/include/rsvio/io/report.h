// report.json: the summary every run writes (user-contract.md, "Files a run writes").
//
//   {"status": "ok" | "failed" | "interrupted", "error": "<one line, when failed or interrupted>",
//    "frames": N, "keyframes": N, "fps": f, "realtime_factor": fps / camera_rate_hz,
//    "stage_ms": {"<stage>": mean ms per call, ...}, "scale": s (VIO only),
//    "eval": {"ate_rmse_m": x, "align": "se3|sim3|none", ...} (when the dataset has ground truth),
//    "dataset": "<dataset folder>", "config": "<config name>", "seed": N, "threads": N,
//    "camera_rate_hz": r, "warnings": [...], "extra": {...}}
// fps counts frames over the wall time of the whole run including image decoding, excluding rendering
// and evaluation (conventions.md, Outputs).
#pragma once
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace rsvio {

struct ReportEval {
  double ate_rmse_m = 0.0;
  std::string align = "se3";
  nlohmann::json details = nlohmann::json::object();  // anything else evaluation reports
};

struct Report {
  std::string status = "ok";
  std::string error;
  long frames = 0;
  long keyframes = 0;
  double fps = 0.0;
  double realtime_factor = 0.0;
  double camera_rate_hz = 0.0;
  std::map<std::string, double> stage_ms;
  std::optional<double> scale;
  std::optional<ReportEval> eval;
  std::string dataset;
  std::string config;
  long seed = 0;
  int threads = 1;
  std::vector<std::string> warnings;
  nlohmann::json extra = nlohmann::json::object();

  bool ok() const { return status == "ok"; }
  nlohmann::json toJson() const;
  static Report fromJson(const nlohmann::json& j, const std::string& origin = "report.json");
  void write(const std::string& path) const;          // throws Error on I/O failure
  static Report read(const std::string& path);        // throws DataError naming the file and key
};

}  // namespace rsvio
