// index.html pages of a run and of a comparison (render_run.h). Plain HTML with inline CSS, no
// scripts, links relative to the page so a folder can be moved, zipped or served as is.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "canvas.h"
#include "rsvio/core/error.h"
#include "rsvio/viz/render_run.h"

namespace rsvio::viz {
namespace fs = std::filesystem;

namespace {

std::string esc(const std::string& s) {
  std::string o;
  o.reserve(s.size());
  for (char c : s) {
    switch (c) {
      case '&': o += "&amp;"; break;
      case '<': o += "&lt;"; break;
      case '>': o += "&gt;"; break;
      case '"': o += "&quot;"; break;
      default: o += c;
    }
  }
  return o;
}

// Path of `target` relative to the folder of `page`, with '/' separators, URL-escaped where needed.
std::string rel(const fs::path& target, const fs::path& page) {
  std::error_code ec;
  const fs::path base = fs::weakly_canonical(fs::absolute(page).parent_path(), ec);
  const fs::path t = fs::weakly_canonical(fs::absolute(target), ec);
  fs::path r = t.lexically_relative(base);
  if (r.empty()) r = t;
  std::string s = r.generic_string();
  std::string o;
  for (char c : s) {
    if (c == ' ') o += "%20";
    else if (c == '#') o += "%23";
    else if (c == '?') o += "%3F";
    else if (c == '%') o += "%25";
    else o += c;
  }
  return esc(o);
}

std::string num(double v, int prec = 4) {
  if (!std::isfinite(v)) return "&ndash;";
  std::ostringstream s;
  s.precision(prec);
  s << v;
  return s.str();
}

const char* kStyle = R"(<style>
body{font-family:-apple-system,"Segoe UI",Helvetica,Arial,sans-serif;margin:24px auto;max-width:1240px;color:#222;padding:0 16px}
h1{font-size:1.6em;margin-bottom:4px}h2{font-size:1.2em;margin-top:28px;border-bottom:1px solid #ddd;padding-bottom:4px}
table{border-collapse:collapse;margin:8px 0}td,th{border:1px solid #ddd;padding:4px 10px;text-align:left;font-size:0.93em}
th{background:#f4f4f4}td.n{text-align:right;font-variant-numeric:tabular-nums}
.badge{display:inline-block;padding:2px 10px;border-radius:10px;color:#fff;font-weight:600;font-size:0.9em}
.ok{background:#2e8b57}.failed{background:#c0392b}.unknown{background:#888}
.err{color:#c0392b;font-weight:600}.muted{color:#777}
.figs{display:grid;grid-template-columns:repeat(auto-fill,minmax(540px,1fr));gap:18px}
figure{margin:0;border:1px solid #e3e3e3;padding:8px;background:#fff}figure img{width:100%;height:auto;display:block}
figure.wide{grid-column:1/-1}figure.wide img{width:auto;max-width:100%}
figcaption{font-size:0.88em;color:#555;margin-top:6px}
.bar{background:#4a90d9;height:10px;display:inline-block}
pre{background:#f7f7f7;padding:10px;overflow:auto;font-size:0.85em}
</style>)";

void writePage(const std::string& path, const std::string& title, const std::string& body) {
  const fs::path p(path);
  if (p.has_parent_path()) fs::create_directories(p.parent_path());
  std::ofstream f(path);
  if (!f) throw Error(path + ": cannot open for writing");
  f << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n<meta name=\"viewport\" "
       "content=\"width=device-width,initial-scale=1\">\n<title>"
    << esc(title) << "</title>\n" << kStyle << "</head>\n<body>\n" << body << "</body></html>\n";
  if (!f) throw Error(path + ": write failed");
}

void figuresSection(std::ostringstream& b, const std::vector<FigureLink>& figures, const std::string& page) {
  if (figures.empty()) {
    b << "<p class=\"muted\">No figures.</p>\n";
    return;
  }
  b << "<div class=\"figs\">\n";
  for (const auto& f : figures) {
    const std::string href = rel(f.path, page);
    b << "<figure" << (f.wide ? " class=\"wide\"" : "") << "><a href=\"" << href << "\"><img src=\"" << href << "\" alt=\"" << esc(fs::path(f.path).filename().string())
      << "\"></a><figcaption>" << esc(f.caption) << "</figcaption></figure>\n";
  }
  b << "</div>\n";
}

void row(std::ostringstream& b, const std::string& k, const std::string& v_html, bool numeric = false) {
  b << "<tr><th>" << esc(k) << "</th><td" << (numeric ? " class=\"n\"" : "") << ">" << v_html << "</td></tr>\n";
}

// Numbers of a JSON object, flattened to "a.b.c" keys (eval details of any shape).
void flatten(const nlohmann::json& j, const std::string& prefix, std::vector<std::pair<std::string, std::string>>& out) {
  if (j.is_object()) {
    for (const auto& [k, v] : j.items()) flatten(v, prefix.empty() ? k : prefix + "." + k, out);
  } else if (j.is_number()) {
    out.emplace_back(prefix, num(j.get<double>(), 6));
  } else if (j.is_string()) {
    out.emplace_back(prefix, esc(j.get<std::string>()));
  } else if (j.is_boolean()) {
    out.emplace_back(prefix, j.get<bool>() ? "true" : "false");
  }
}

}  // namespace

void writeRunIndex(const std::string& index_path, const io::Snapshot& s, const std::vector<FigureLink>& figures,
                   const std::vector<std::string>& problems) {
  std::ostringstream b;
  const std::string status = s.summary.status;
  const std::string cls = status == "ok" ? "ok" : status == "failed" ? "failed" : "unknown";
  b << "<h1>Run " << esc(s.name) << " <span class=\"badge " << cls << "\">" << esc(status) << "</span></h1>\n";
  b << "<p class=\"muted\">" << esc(fs::absolute(s.run_dir).lexically_normal().string()) << "</p>\n";
  if (!s.summary.error.empty()) b << "<p class=\"err\">" << esc(s.summary.error) << "</p>\n";

  b << "<h2>Summary</h2>\n<table>\n";
  row(b, "status", esc(status));
  row(b, "frames", s.summary.frames >= 0 ? std::to_string(s.summary.frames) : "&ndash;", true);
  row(b, "keyframes", s.summary.keyframes >= 0 ? std::to_string(s.summary.keyframes) : "&ndash;", true);
  row(b, "fps (frames per wall-clock second)", num(s.summary.fps), true);
  row(b, "realtime factor", num(s.summary.realtime_factor), true);
  row(b, "scale (metres per visual unit)", num(s.summary.scale), true);
  row(b, "pose frame", io::poseFrameName(s.poseFrame()));
  row(b, "poses / keyframe poses / points",
      std::to_string(s.trajectory.size()) + " / " + std::to_string(s.keyframes.size()) + " / " + std::to_string(s.points.size()), true);
  row(b, "dataset", s.summary.dataset.empty() ? "&ndash;" : esc(s.summary.dataset));
  row(b, "ground truth", s.ground_truth_source.empty() ? "&ndash;" : esc(s.ground_truth_source));
  b << "</table>\n";

  b << "<h2>Accuracy</h2>\n";
  if (std::isfinite(s.summary.ate_rmse_m) || s.errors) {
    b << "<table>\n";
    if (std::isfinite(s.summary.ate_rmse_m)) row(b, "ATE RMSE (report.json) [m]", num(s.summary.ate_rmse_m), true);
    if (!s.summary.align.empty()) row(b, "alignment (report.json)", esc(s.summary.align));
    if (s.errors) {
      const auto& e = *s.errors;
      row(b, "ATE RMSE (recomputed on " + e.aligned_on + ") [m]", num(e.ate_m.rmse), true);
      row(b, "ATE mean / median / max [m]", num(e.ate_m.mean) + " / " + num(e.ate_m.median) + " / " + num(e.ate_m.max), true);
      row(b, "pairs", std::to_string(e.ate_m.n), true);
      row(b, "alignment", std::string(eval::alignModeName(e.alignment.mode)) + " (" + esc(e.align_reason) + "), scale " +
                              num(e.alignment.scale, 6));
    }
    b << "</table>\n";
    const auto ev = s.report.find("eval");
    if (ev != s.report.end() && ev->is_object()) {
      std::vector<std::pair<std::string, std::string>> kv;
      flatten(*ev, "", kv);
      if (kv.size() > 2) {
        b << "<details><summary>report.json &rarr; eval (" << kv.size() << " values)</summary><table>\n";
        for (const auto& [k, v] : kv) b << "<tr><th>" << esc(k) << "</th><td class=\"n\">" << v << "</td></tr>\n";
        b << "</table></details>\n";
      }
    }
  } else {
    b << "<p class=\"muted\">No ground truth: no accuracy figures.</p>\n";
  }

  b << "<h2>Stage times</h2>\n";
  if (s.summary.stage_ms.empty()) {
    b << "<p class=\"muted\">report.json has no stage_ms.</p>\n";
  } else {
    double mx = 0;
    for (const auto& kv : s.summary.stage_ms) mx = std::max(mx, kv.second);
    b << "<table><tr><th>stage</th><th>mean per call [ms]</th><th></th></tr>\n";
    for (const auto& [k, v] : s.summary.stage_ms) {
      const int w = mx > 0 ? static_cast<int>(std::lround(240.0 * v / mx)) : 0;
      b << "<tr><td>" << esc(k) << "</td><td class=\"n\">" << num(v) << "</td><td><span class=\"bar\" style=\"width:" << w
        << "px\"></span></td></tr>\n";
    }
    b << "</table>\n";
  }

  b << "<h2>Figures</h2>\n";
  figuresSection(b, figures, index_path);

  b << "<h2>Files</h2>\n<ul>\n";
  for (const char* f : {"report.json", "config.json", "trajectory.tum", "keyframes.tum", "states.csv", "points.ply",
                        "diagnostics.bin", "eval.json", "error_over_time.csv"}) {
    const fs::path p = fs::path(s.run_dir) / f;
    if (fs::exists(p)) b << "<li><a href=\"" << rel(p, index_path) << "\">" << f << "</a></li>\n";
  }
  b << "</ul>\n";
  if (!problems.empty() || !s.notes.empty()) {
    b << "<h2>Notes</h2>\n<ul>\n";
    for (const auto& p : problems) b << "<li class=\"err\">" << esc(p) << "</li>\n";
    for (const auto& n : s.notes) b << "<li class=\"muted\">" << esc(n) << "</li>\n";
    b << "</ul>\n";
  }
  if (!s.report.empty()) b << "<details><summary>report.json</summary><pre>" << esc(s.report.dump(2)) << "</pre></details>\n";
  writePage(index_path, "rsvio run " + s.name, b.str());
}

void writeCompareIndex(const std::string& index_path, const std::string& title, const std::vector<CompareRun>& runs,
                       const std::vector<FigureLink>& figures, const std::vector<std::string>& notes) {
  std::ostringstream b;
  b << "<h1>" << esc(title) << "</h1>\n";
  const CompareGrid g = makeCompareGrid(runs);
  b << "<p class=\"muted\">" << g.configs.size() << " configuration(s), " << g.sequences.size() << " sequence(s), "
    << g.runs << " run(s) each.</p>\n";

  b << "<h2>Per configuration</h2>\n<table><tr><th>configuration</th><th>runs</th><th>failed</th><th>median ATE [m]</th>"
       "<th>mean ATE [m]</th><th>best / worst [m]</th></tr>\n";
  for (const auto& cfg : g.configs) {
    std::vector<double> v;
    int n = 0, failed = 0;
    for (const auto& r : runs) {
      if (r.config != cfg) continue;
      ++n;
      if (r.failed) ++failed;
      else if (std::isfinite(r.ate_m)) v.push_back(r.ate_m);
    }
    std::sort(v.begin(), v.end());
    double med = kNaN, mean = kNaN;
    if (!v.empty()) {
      med = v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
      mean = 0;
      for (double x : v) mean += x;
      mean /= v.size();
    }
    b << "<tr><td>" << esc(cfg) << "</td><td class=\"n\">" << n << "</td><td class=\"n" << (failed ? " err" : "") << "\">"
      << failed << "</td><td class=\"n\">" << num(med) << "</td><td class=\"n\">" << num(mean) << "</td><td class=\"n\">"
      << (v.empty() ? "&ndash;" : num(v.front()) + " / " + num(v.back())) << "</td></tr>\n";
  }
  b << "</table>\n";

  b << "<h2>Figures</h2>\n";
  figuresSection(b, figures, index_path);

  b << "<h2>Runs</h2>\n<table><tr><th>configuration</th><th>sequence</th><th>run #</th><th>status</th><th>ATE [m]</th>"
       "<th>page</th><th>error</th></tr>\n";
  for (const auto& r : runs) {
    std::string link = "&ndash;";
    if (!r.run_dir.empty()) {
      const fs::path page = fs::path(r.run_dir) / "index.html";
      const fs::path target = fs::exists(page) ? page : fs::path(r.run_dir);
      link = "<a href=\"" + rel(target, index_path) + "\">" + esc(fs::path(r.run_dir).filename().string()) + "</a>";
    }
    b << "<tr><td>" << esc(r.config) << "</td><td>" << esc(r.sequence) << "</td><td class=\"n\">" << r.run << "</td><td>"
      << (r.failed ? "<span class=\"badge failed\">failed</span>" : "<span class=\"badge ok\">ok</span>") << "</td><td class=\"n\">"
      << num(r.ate_m) << "</td><td>" << link << "</td><td class=\"err\">" << esc(r.error) << "</td></tr>\n";
  }
  b << "</table>\n";
  if (!notes.empty()) {
    b << "<h2>Notes</h2>\n<ul>\n";
    for (const auto& n : notes) b << "<li>" << esc(n) << "</li>\n";
    b << "</ul>\n";
  }
  writePage(index_path, title, b.str());
}

}  // namespace rsvio::viz
