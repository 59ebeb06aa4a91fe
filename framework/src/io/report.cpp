#include "rsvio/io/report.h"

#include <fstream>
#include <sstream>

#include "rsvio/core/error.h"
#include "rsvio/io/atomic_file.h"

namespace rsvio {

nlohmann::json Report::toJson() const {
  nlohmann::json j;
  j["status"] = status;
  if (!error.empty()) j["error"] = error;
  j["frames"] = frames;
  j["keyframes"] = keyframes;
  j["fps"] = fps;
  j["realtime_factor"] = realtime_factor;
  j["camera_rate_hz"] = camera_rate_hz;
  j["stage_ms"] = stage_ms;
  if (scale) j["scale"] = *scale;
  if (eval) {
    nlohmann::json e = eval->details;
    e["ate_rmse_m"] = eval->ate_rmse_m;
    e["align"] = eval->align;
    j["eval"] = e;
  }
  j["dataset"] = dataset;
  j["config"] = config;
  j["seed"] = seed;
  j["threads"] = threads;
  j["warnings"] = warnings;
  if (!extra.empty()) j["extra"] = extra;
  return j;
}

Report Report::fromJson(const nlohmann::json& j, const std::string& origin) {
  if (!j.is_object()) throw DataError(origin + ": expected a JSON object");
  Report r;
  try {
    if (!j.contains("status")) throw DataError(origin + ": missing key \"status\"");
    r.status = j.at("status").get<std::string>();
    if (r.status != "ok" && r.status != "failed" && r.status != "interrupted")
      throw DataError(origin + ": status: expected \"ok\", \"failed\" or \"interrupted\", found \"" + r.status +
                      "\"");
    r.error = j.value("error", "");
    r.frames = j.value("frames", 0L);
    r.keyframes = j.value("keyframes", 0L);
    r.fps = j.value("fps", 0.0);
    r.realtime_factor = j.value("realtime_factor", 0.0);
    r.camera_rate_hz = j.value("camera_rate_hz", 0.0);
    if (j.contains("stage_ms")) r.stage_ms = j.at("stage_ms").get<std::map<std::string, double>>();
    if (j.contains("scale") && !j.at("scale").is_null()) r.scale = j.at("scale").get<double>();
    if (j.contains("eval") && j.at("eval").is_object()) {
      ReportEval e;
      e.details = j.at("eval");
      e.ate_rmse_m = e.details.at("ate_rmse_m").get<double>();
      e.align = e.details.value("align", "se3");
      e.details.erase("ate_rmse_m");
      e.details.erase("align");
      r.eval = e;
    }
    r.dataset = j.value("dataset", "");
    r.config = j.value("config", "");
    r.seed = j.value("seed", 0L);
    r.threads = j.value("threads", 1);
    if (j.contains("warnings")) r.warnings = j.at("warnings").get<std::vector<std::string>>();
    if (j.contains("extra")) r.extra = j.at("extra");
  } catch (const nlohmann::json::exception& e) {
    throw DataError(origin + ": " + e.what());
  }
  return r;
}

void Report::write(const std::string& path) const {
  const std::string text = toJson().dump(2) + "\n";
  io::writeFileAtomic(path, [&](std::ostream& out) { out << text; }, "report");
}

Report Report::read(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw DataError(path + ": cannot open report");
  std::stringstream ss;
  ss << in.rdbuf();
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(ss.str());
  } catch (const nlohmann::json::parse_error& e) {
    throw DataError(path + ": invalid JSON (" + std::string(e.what()) + ")");
  }
  return fromJson(j, path);
}

}  // namespace rsvio
