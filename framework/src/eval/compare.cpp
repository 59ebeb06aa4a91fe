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
#include <csignal>

#include "rsvio/config/config.h"
#include "rsvio/core/error.h"
#include "rsvio/eval/evaluate_files.h"
#include "rsvio/io/atomic_file.h"
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
  if (r.status == "interrupted" || r.status == "not run") return s + r.status + " (" + r.error + ")";
  if (r.kept) s = s + "kept from the earlier comparison, ";
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

std::string fnv1a(const std::string& bytes) {
  uint64_t h = 1469598103934665603ull;
  for (unsigned char c : bytes) {
    h ^= c;
    h *= 1099511628211ull;
  }
  char buf[17];
  std::snprintf(buf, sizeof(buf), "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

std::string configHash(const std::string& path, const std::vector<std::string>& sets) {
  try {
    return fnv1a(loadConfigWithSets(path, sets).dump());
  } catch (const std::exception&) {
    std::ifstream in(path, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    for (const auto& x : sets) bytes += "\n--set " + x;
    return fnv1a(bytes);
  }
}

std::string absolutePath(const std::string& p) {
  std::error_code ec;
  auto a = fs::absolute(p, ec);
  return ec ? p : a.lexically_normal().string();
}

// --resume: the record of an earlier invocation's finished run, when its job.json matches this job.
std::optional<RunRecord> keptRun(const CompareJob& job) {
  const fs::path dir(job.out_dir);
  std::error_code ec;
  if (!fs::is_regular_file(dir / "job.json", ec) || !fs::is_regular_file(dir / "report.json", ec)) return std::nullopt;
  std::ifstream jin(dir / "job.json");
  const auto id = nlohmann::json::parse(jin, nullptr, false);
  if (id.is_discarded() || id != jobIdentity(job)) return std::nullopt;
  std::ifstream rin(dir / "report.json");
  const auto rep = nlohmann::json::parse(rin, nullptr, false);
  if (rep.is_discarded() || !rep.is_object()) return std::nullopt;
  const std::string status = stringAt(rep, "status");
  if (status != "ok" && status != "failed") return std::nullopt;
  ChildOutcome oc;
  oc.kind = ChildOutcome::Kind::kExited;
  oc.code = status == "ok" ? 0 : 1;
  RunRecord r = collectRun(job, oc);
  r.kept = true;
  return r;
}

}  // namespace

nlohmann::json jobIdentity(const CompareJob& job) {
  return {{"config", absolutePath(job.config_path)}, {"config_hash", job.config_hash},
          {"data", absolutePath(job.dataset_dir)},   {"seed", job.run},
          {"sets", job.sets}};
}

size_t CompareResult::unfinished() const {
  return static_cast<size_t>(std::count_if(runs.begin(), runs.end(), [](const RunRecord& r) {
    return r.status == "interrupted" || r.status == "not run";
  }));
}

size_t CompareResult::kept() const {
  return static_cast<size_t>(std::count_if(runs.begin(), runs.end(), [](const RunRecord& r) { return r.kept; }));
}

std::vector<CompareJob> planCompareJobs(const std::vector<std::string>& configs, const std::vector<std::string>& datasets,
                                        int runs, const std::string& out_root, const std::vector<std::string>& sets) {
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
    const std::string hash = configHash(configs[c], sets);
    for (size_t d = 0; d < datasets.size(); ++d) {
      for (int k = 0; k < runs; ++k) {
        CompareJob j;
        j.config_path = configs[c];
        j.config_name = cfg_names[c];
        j.dataset_dir = datasets[d];
        j.dataset_name = ds_names[d];
        j.run = k;
        j.sets = sets;
        j.config_hash = hash;
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
  for (const auto& x : job.sets) {
    argv.push_back("--set");
    argv.push_back(x);
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
  if (outcome.kind == ChildOutcome::Kind::kNotStarted) {
    r.status = "not run";
    r.error = outcome.describe();
    return r;
  }
  const std::string rep_status = report ? stringAt(*report, "status") : "";
  if (rep_status == "interrupted" || (outcome.kind == ChildOutcome::Kind::kExited && outcome.code == 130) ||
      (outcome.kind == ChildOutcome::Kind::kSignaled && (outcome.code == SIGTERM || outcome.code == SIGKILL ||
                                                         outcome.code == SIGINT) && outcome.stopped)) {
    r.status = "interrupted";
    const std::string rep_error = report ? stringAt(*report, "error") : "";
    r.error = rep_error.empty() ? outcome.describe() : rep_error;
    return r;
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
  r.status = "ok";
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
  return static_cast<size_t>(
      std::count_if(runs.begin(), runs.end(), [](const RunRecord& r) { return r.status == "failed"; }));
}

std::vector<GroupSummary> summariseRuns(const std::vector<RunRecord>& runs) {
  std::vector<GroupSummary> groups;
  std::map<std::pair<std::string, std::string>, size_t> index;
  std::vector<std::vector<double>> ates, fpss;
  for (const auto& r : runs) {
    if (r.status == "interrupted" || r.status == "not run") continue;  // the summary is of finished runs
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
  CompareResult res;
  res.runs.resize(jobs.size());
  size_t done = 0;
  std::vector<ChildSpec> specs;
  std::vector<size_t> spec_job;  // job index of each spec
  for (size_t i = 0; i < jobs.size(); ++i) {
    const auto& j = jobs[i];
    if (options.resume) {
      if (auto kept = keptRun(j)) {
        res.runs[i] = *kept;
        ++done;
        if (progress) *progress << progressLine(done, jobs.size(), res.runs[i]) << std::endl;
        continue;
      }
    }
    // A folder left by an earlier comparison must not lend its report.json to this run.
    std::error_code ec;
    fs::remove_all(j.out_dir, ec);
    fs::create_directories(j.out_dir, ec);
    if (ec) throw Error(j.out_dir + ": cannot create the run folder (" + ec.message() + ")");
    const std::string id = jobIdentity(j).dump(2) + "\n";
    io::writeFileAtomic((fs::path(j.out_dir) / "job.json").string(), [&](std::ostream& o) { o << id; }, "job");
    specs.push_back({argv_builder(j), (fs::path(j.out_dir) / "log.txt").string()});
    spec_job.push_back(i);
  }
  PoolOptions pool;
  pool.max_workers = options.jobs;
  pool.timeout_s = options.timeout_s;
  pool.stop_level = [&]() {
    const int level = options.stop_level ? options.stop_level() : 0;
    if (level > 0) res.interrupted = true;
    return level;
  };
  runChildProcesses(specs, pool, {}, [&](size_t k, const ChildOutcome& oc) {
    const size_t i = spec_job[k];
    res.runs[i] = collectRun(jobs[i], oc);
    ++done;
    if (progress) *progress << progressLine(done, jobs.size(), res.runs[i]) << std::endl;
  });
  res.groups = summariseRuns(res.runs);
  return res;
}

}  // namespace rsvio::eval
