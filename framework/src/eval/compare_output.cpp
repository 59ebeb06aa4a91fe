// Table, JSON and CSV of a comparison grid (rsvio/eval/compare.h).
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "rsvio/core/error.h"
#include "rsvio/eval/compare.h"
#include "rsvio/io/atomic_file.h"

namespace rsvio::eval {
namespace {

std::string num(const std::optional<double>& v, const char* fmt = "%.6f") {
  if (!v) return "";
  char buf[64];
  std::snprintf(buf, sizeof(buf), fmt, *v);
  return buf;
}

nlohmann::json jnum(const std::optional<double>& v) { return v ? nlohmann::json(*v) : nlohmann::json(nullptr); }

std::string csvField(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) {
    if (c == '"') out += '"';
    out += (c == '\n' || c == '\r') ? ' ' : c;
  }
  return out + "\"";
}

std::string groupStatus(const GroupSummary& g) {
  return g.failed == 0 ? "ok" : (g.failed == g.runs ? "all_failed" : "some_failed");
}

}  // namespace

std::string formatCompareTable(const CompareResult& r) {
  size_t wc = 6, wd = 7;
  for (const auto& g : r.groups) {
    wc = std::max(wc, g.config_name.size());
    wd = std::max(wd, g.dataset_name.size());
  }
  std::ostringstream o;
  char buf[512];
  std::snprintf(buf, sizeof(buf), "%-*s  %-*s  %4s  %6s  %14s  %12s  %10s\n", int(wc), "config", int(wd), "dataset",
                "runs", "failed", "ATE median (m)", "ATE mean (m)", "fps median");
  o << buf;
  for (const auto& g : r.groups) {
    const std::string med = g.ate_median_m ? num(g.ate_median_m) : "-";
    const std::string mn = g.ate_mean_m ? num(g.ate_mean_m) : "-";
    const std::string fps = g.fps_median ? num(g.fps_median, "%.1f") : "-";
    std::snprintf(buf, sizeof(buf), "%-*s  %-*s  %4zu  %6zu  %14s  %12s  %10s\n", int(wc), g.config_name.c_str(), int(wd),
                  g.dataset_name.c_str(), g.runs, g.failed, med.c_str(), mn.c_str(), fps.c_str());
    o << buf;
  }
  o << r.runs.size() - r.failed() - r.unfinished() << " of " << r.runs.size() << " runs ok";
  if (r.failed()) o << ", " << r.failed() << " failed (errors in compare.json / compare.csv, logs in runs/*/*/*/log.txt)";
  if (r.unfinished()) o << ", " << r.unfinished() << " not finished (interrupted; rerun with --resume to finish them)";
  if (r.kept()) o << "; " << r.kept() << " kept from the earlier comparison (--resume)";
  o << "\n";
  return o.str();
}

nlohmann::json compareToJson(const CompareResult& r) {
  using nlohmann::json;
  json summary = json::array(), runs = json::array();
  for (const auto& g : r.groups) {
    summary.push_back({{"config", g.config_name},
                       {"dataset", g.dataset_name},
                       {"status", groupStatus(g)},
                       {"runs", g.runs},
                       {"failed", g.failed},
                       {"runs_with_ate", g.with_ate},
                       {"ate_median_m", jnum(g.ate_median_m)},
                       {"ate_mean_m", jnum(g.ate_mean_m)},
                       {"fps_median", jnum(g.fps_median)},
                       {"fps_mean", jnum(g.fps_mean)}});
  }
  for (const auto& x : r.runs) {
    runs.push_back({{"config", x.job.config_name},
                    {"config_path", x.job.config_path},
                    {"dataset", x.job.dataset_name},
                    {"dataset_dir", x.job.dataset_dir},
                    {"run", x.job.run},
                    {"seed", x.job.run},
                    {"status", x.status},
                    {"kept", x.kept},
                    {"error", x.error},
                    {"ate_rmse_m", jnum(x.ate_rmse_m)},
                    {"align", x.align},
                    {"eval_note", x.eval_note},
                    {"fps", jnum(x.fps)},
                    {"realtime_factor", jnum(x.realtime_factor)},
                    {"wall_s", x.wall_s},
                    {"out_dir", x.job.out_dir},
                    {"log", x.log_path}});
  }
  return {{"runs_total", r.runs.size()}, {"failed", r.failed()},   {"unfinished", r.unfinished()},
          {"interrupted", r.interrupted}, {"summary", summary},     {"runs", runs}};
}

void writeCompareOutputs(const std::string& out_dir, const CompareResult& r, const nlohmann::json& invocation) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::create_directories(out_dir, ec);
  const std::string json_path = (fs::path(out_dir) / "compare.json").string();
  nlohmann::json j = compareToJson(r);
  if (!invocation.is_null()) j["invocation"] = invocation;
  const std::string json_text = j.dump(2) + "\n";
  io::writeFileAtomic(json_path, [&](std::ostream& f) { f << json_text; }, "comparison");
  const std::string csv_path = (fs::path(out_dir) / "compare.csv").string();
  io::writeFileAtomic(csv_path, [&](std::ostream& f) {
  // Summary rows fill the columns up to fps_mean, run rows those from ate_rmse_m on.
  f << "row,config,dataset,run,status,runs,failed,ate_median_m,ate_mean_m,fps_median,fps_mean,"
       "ate_rmse_m,fps,realtime_factor,align,error\n";
  for (const auto& g : r.groups) {
    f << "summary," << csvField(g.config_name) << "," << csvField(g.dataset_name) << ",," << groupStatus(g) << ","
      << g.runs << "," << g.failed << "," << num(g.ate_median_m, "%.9g") << "," << num(g.ate_mean_m, "%.9g") << ","
      << num(g.fps_median, "%.6g") << "," << num(g.fps_mean, "%.6g") << ",,,,,\n";
  }
  for (const auto& x : r.runs) {
    f << "run," << csvField(x.job.config_name) << "," << csvField(x.job.dataset_name) << "," << x.job.run << ","
      << x.status << ",,,,,,," << num(x.ate_rmse_m, "%.9g") << "," << num(x.fps, "%.6g") << ","
      << num(x.realtime_factor, "%.6g") << "," << csvField(x.align) << "," << csvField(x.error) << "\n";
  }
  }, "comparison table");
}

}  // namespace rsvio::eval
