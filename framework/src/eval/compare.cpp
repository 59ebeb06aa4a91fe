// Comparison grid: planning, running and reading back runs (rsvio/eval/compare.h).
#include "rsvio/eval/compare.h"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <ostream>
#include <set>

#include "rsvio/core/error.h"
#include "rsvio/eval/evaluate_files.h"
#include "rsvio/io/trajectory.h"

namespace rsvio::eval {
namespace fs = std::filesystem;
namespace {

std::string safeName(std::string s) {
  for (char& c : s) {
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_' || c == '-')) c = '_';
  }
  return s.empty() ? std::string("unnamed") : s;
}

// Names are folder names under runs/: two configs named a.json in different folders become a, a_2.
std::vector<std::string> uniqueNames(const std::vector<std::string>& raw) {
  std::vector<std::string> out;
  std::set<std::string> used;
  for (const auto& r : raw) {
    std::string name = safeName(r), candidate = name;
    for (int k = 2; used.count(candidate); ++k) candidate = name + "_" + std::to_string(k);
    used.insert(candidate);
    out.push_back(candidate);
  }
  return out;
}

std::string lastLogLine(const std::string& path) {
  std::ifstream in(path);
  std::string line, last;
  while (std::getline(in, line)) {
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ' || line.back() == '\t')) line.pop_back();
    if (!line.empty()) last = line;
  }
  if (last.size() > 300) last = last.substr(0, 297) + "...";
  return last;
}

std::optional<double> numberAt(const nlohmann::json& j, const char* key) {
  if (j.is_object() && j.contains(key) && j[key].is_number()) return j[key].get<double>();
  return std::nullopt;
}

std::string stringAt(const nlohmann::json& j, const char* key) {
  if (j.is_object() && j.contains(key) && j[key].is_string()) return j[key].get<std::string>();
  return "";
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t m = v.size() / 2;
  return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

double mean(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return s / static_cast<double>(v.size());
}

// Own evaluation when the report has no eval: keyframes first (the paper's eq. 35 is over keyframes).
void evaluateRunHere(const CompareJob& job, RunRecord& r) {
  if (!io::findDatasetGroundTruth(job.dataset_dir)) {
    r.eval_note = "no ATE: the dataset has no ground truth";
    return;
  }
  for (const char* name : {"keyframes.tum", "trajectory.tum"}) {
    const fs::path est = fs::path(job.out_dir) / name;
    std::error_code ec;
    if (!fs::is_regular_file(est, ec)) continue;
    try {
      FileEvalRequest req;
      req.dataset_dir = job.dataset_dir;
      req.est_path = est.string();
      const auto outcome = evaluateFiles(req);
      r.ate_rmse_m = outcome.result.ate_m.rmse;
      r.align = alignModeName(outcome.result.alignment.mode);
      r.eval_note = std::string("evaluated ") + name + " against the dataset's ground truth";
    } catch (const std::exception& e) {
      r.eval_note = std::string("no ATE: evaluating ") + name + " failed: " + e.what();
    }
    return;
  }
  r.eval_note = "no ATE: the report has no eval and the run wrote no keyframes.tum or trajectory.tum";
}

std::string progressLine(size_t done, size_t total, const RunRecord& r) {
  char buf[160];
  std::snprintf(buf, sizeof(buf), "[%zu/%zu] %s on %s run %d: ", done, total, r.job.config_name.c_str(),
                r.job.dataset_name.c_str(), r.job.run);
  std::string s = buf;
  if (!r.ok) return s + "FAILED (" + r.error + ")";
  s += "ok";
  if (r.ate_rmse_m) {
    std::snprintf(buf, sizeof(buf), " ATE %.4g m", *r.ate_rmse_m);
    s += buf;
  } else {
    s += " (" + r.eval_note + ")";
  }
  if (r.fps) {
    std::snprintf(buf, sizeof(buf), " %.1f fps", *r.fps);
    s += buf;
  }
  return s;
}

}  // namespace

std::vector<CompareJob> planCompareJobs(const std::vector<std::string>& configs, const std::vector<std::string>& datasets,
                                        int runs, const std::string& out_root) {
  std::vector<std::string> cfg_raw, ds_raw;
  for (const auto& c : configs) cfg_raw.push_back(fs::path(c).stem().string());
  for (const auto& d : datasets) {
    fs::path p = fs::path(d).lexically_normal();
    if (p.filename().empty()) p = p.parent_path();  // "seq01/" -> "seq01"
    ds_raw.push_back(p.filename().string());
  }
  const auto cfg_names = uniqueNames(cfg_raw), ds_names = uniqueNames(ds_raw);
  std::vector<CompareJob> jobs;
  for (size_t c = 0; c < configs.size(); ++c) {
    for (size_t d = 0; d < datasets.size(); ++d) {
      for (int k = 0; k < runs; ++k) {
        CompareJob j;
        j.config_path = configs[c];
        j.config_name = cfg_names[c];
        j.dataset_dir = datasets[d];
        j.dataset_name = ds_names[d];
        j.run = k;
        j.out_dir = (fs::path(out_root) / "runs" / j.config_name / j.dataset_name / std::to_string(k)).string();
        jobs.push_back(j);
      }
    }
  }
  return jobs;
}

std::vector<std::string> rsvioRunArgv(const std::string& program, const std::vector<std::string>& pre_args,
                                      const CompareJob& job) {
  std::vector<std::string> argv{program};
  argv.insert(argv.end(), pre_args.begin(), pre_args.end());
  for (const std::string& a : {std::string("run"), std::string("--config"), job.config_path, std::string("--data"),
                               job.dataset_dir, std::string("--out"), job.out_dir, std::string("--seed"),
                               std::to_string(job.run)}) {
    argv.push_back(a);
  }
  return argv;
}

RunRecord collectRun(const CompareJob& job, const ChildOutcome& outcome) {
  RunRecord r;
  r.job = job;
  r.wall_s = outcome.wall_s;
  r.log_path = (fs::path(job.out_dir) / "log.txt").string();
  const fs::path report_path = fs::path(job.out_dir) / "report.json";
  std::optional<nlohmann::json> report;
  std::string report_problem;
  std::error_code ec;
  if (fs::is_regular_file(report_path, ec)) {
    std::ifstream in(report_path);
    auto j = nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false);
    if (j.is_discarded() || !j.is_object()) {
      report_problem = report_path.string() + ": not a JSON object";
    } else {
      report = std::move(j);
    }
  }
  if (!outcome.ok()) {
    std::string why = outcome.describe();
    const std::string rep_error = report ? stringAt(*report, "error") : "";
    if (!rep_error.empty()) {
      why = rep_error + " (" + why + ")";
    } else {
      const std::string last = lastLogLine(r.log_path);
      if (!last.empty()) why += ": " + last;
    }
    r.error = why;
    return r;
  }
  if (!report) {
    r.error = report_problem.empty() ? "exit code 0 but no report.json was written" : report_problem;
    return r;
  }
  const std::string status = stringAt(*report, "status");
  if (status != "ok") {
    const std::string rep_error = stringAt(*report, "error");
    r.error = status == "failed" ? (rep_error.empty() ? "report.json: status failed, no error given" : rep_error)
                                 : "report.json: status '" + status + "', expected 'ok' or 'failed'";
    return r;
  }
  r.ok = true;
  r.fps = numberAt(*report, "fps");
  r.realtime_factor = numberAt(*report, "realtime_factor");
  const nlohmann::json ev = report->contains("eval") ? (*report)["eval"] : nlohmann::json();
  if (auto ate = numberAt(ev, "ate_rmse_m")) {
    r.ate_rmse_m = ate;
    r.align = stringAt(ev, "align");
    r.eval_note = "report.json";
  } else {
    evaluateRunHere(job, r);
  }
  return r;
}

size_t CompareResult::failed() const {
  return static_cast<size_t>(std::count_if(runs.begin(), runs.end(), [](const RunRecord& r) { return !r.ok; }));
}

std::vector<GroupSummary> summariseRuns(const std::vector<RunRecord>& runs) {
  std::vector<GroupSummary> groups;
  std::map<std::pair<std::string, std::string>, size_t> index;
  std::vector<std::vector<double>> ates, fpss;
  for (const auto& r : runs) {
    const auto key = std::make_pair(r.job.config_name, r.job.dataset_name);
    auto it = index.find(key);
    if (it == index.end()) {
      it = index.emplace(key, groups.size()).first;
      GroupSummary g;
      g.config_name = key.first;
      g.dataset_name = key.second;
      groups.push_back(g);
      ates.emplace_back();
      fpss.emplace_back();
    }
    auto& g = groups[it->second];
    ++g.runs;
    if (!r.ok) {
      ++g.failed;
      continue;
    }
    if (r.ate_rmse_m) ates[it->second].push_back(*r.ate_rmse_m);
    if (r.fps) fpss[it->second].push_back(*r.fps);
  }
  for (size_t i = 0; i < groups.size(); ++i) {
    groups[i].with_ate = ates[i].size();
    if (!ates[i].empty()) {
      groups[i].ate_median_m = median(ates[i]);
      groups[i].ate_mean_m = mean(ates[i]);
    }
    if (!fpss[i].empty()) {
      groups[i].fps_median = median(fpss[i]);
      groups[i].fps_mean = mean(fpss[i]);
    }
  }
  return groups;
}

CompareResult runCompare(const std::vector<CompareJob>& jobs, const RunArgvBuilder& argv_builder,
                         const CompareOptions& options, std::ostream* progress) {
  std::vector<ChildSpec> specs;
  for (const auto& j : jobs) {
    // A folder left by an earlier comparison must not lend its report.json to this run.
    std::error_code ec;
    fs::remove_all(j.out_dir, ec);
    fs::create_directories(j.out_dir, ec);
    if (ec) throw Error(j.out_dir + ": cannot create the run folder (" + ec.message() + ")");
    specs.push_back({argv_builder(j), (fs::path(j.out_dir) / "log.txt").string()});
  }
  CompareResult res;
  res.runs.resize(jobs.size());
  size_t done = 0;
  PoolOptions pool;
  pool.max_workers = options.jobs;
  pool.timeout_s = options.timeout_s;
  runChildProcesses(specs, pool, {}, [&](size_t i, const ChildOutcome& oc) {
    res.runs[i] = collectRun(jobs[i], oc);
    ++done;
    if (progress) *progress << progressLine(done, jobs.size(), res.runs[i]) << std::endl;
  });
  res.groups = summariseRuns(res.runs);
  return res;
}

}  // namespace rsvio::eval
