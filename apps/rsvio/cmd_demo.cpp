// rsvio demo [--out DIR] [--reuse-data]: the main job on a built-in synthetic sequence.
//   1. simulate configs/sim/demo.json (a rolling shutter hidden from the calibration) afresh into <out>/data,
//      or with --reuse-data reuse <out>/data when it was simulated before from the same effective config and seed
//      (written to <out>/data.partial and renamed when complete, so a half-written dataset is never reused),
//   2. run the default model configs/default.json on it (evaluated against the ground truth) and render,
//   3. diagnose the run from its folder alone (rsvio diagnose): verdict, ranking, the line to add,
//   4. run again with the named line (when there is one) and render,
//   5. compare (rsvio diagnose --against): ATE before and after, is the evidence gone,
// then a few lines: verdict, line added, ATE before and after, figure paths.
// Exit 0 once the story is told, also when a model fails on the sequence (that is what the demo shows);
// non-zero when a step could not be done (simulation, config, output folder).
#include <chrono>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <filesystem>
#include <iostream>

#include "commands.h"
#include "diagnose.h"
#include "render_hook.h"
#include "run_summary.h"
#include "rsvio/core/error.h"
#include "rsvio/pipeline/run.h"
#include "rsvio/plugin/host.h"
#include "rsvio/sim/simulator.h"

namespace fs = std::filesystem;

namespace rsvio::app {

namespace {

// configs/ of this build: $RSVIO_CONFIG_DIR, else the source tree the binary was built from.
std::string configDir() {
  if (const char* env = std::getenv("RSVIO_CONFIG_DIR")) return env;
  return RSVIO_DEFAULT_CONFIG_DIR;
}

void printAssembled(const nlohmann::json& cfg) {
  std::printf("  assembled pipeline '%s':\n", cfg["name"].get<std::string>().c_str());
  for (const char* slot : {"source", "camera", "shutter", "solver"})
    if (cfg.contains(slot)) std::printf("    %-12s %s\n", slot, cfg[slot]["plugin"].get<std::string>().c_str());
  for (const char* multi : {"photometric", "motion"}) {
    std::string members;
    for (const auto& [name, s] : cfg[multi].items())
      members += (members.empty() ? "" : ", ") + name + "=" + s["plugin"].get<std::string>();
    std::printf("    %-12s %s\n", multi, members.empty() ? "(none)" : members.c_str());
  }
}

// The dataset of the demo: reused when <out>/data was simulated before from the same effective config
// (seed included), else simulated into <out>/data.partial and renamed into place once complete, so an
// interrupted simulation never leaves a dataset that looks whole.
bool prepareData(const std::string& sim_cfg, const std::string& data, bool fresh, PluginHost& host) {
  const nlohmann::json eff = sim::loadSimConfig(sim_cfg, {}, std::nullopt, host);
  const fs::path stamp = fs::path(data) / "rsvio_demo_sim_config.json";
  if (!fresh && fs::exists(stamp) && fs::exists(fs::path(data) / "mav0")) {
    std::ifstream in(stamp);
    nlohmann::json before;
    try {
      before = nlohmann::json::parse(in);
    } catch (const std::exception&) {
    }
    if (before == eff) return true;
  }
  const fs::path partial = data + ".partial";
  fs::remove_all(partial);
  {
    sim::Simulator simulator(eff, host);
    simulator.write(partial.string());
  }
  {
    std::ofstream out(partial / "rsvio_demo_sim_config.json");
    out << eff.dump(2) << "\n";
    if (!out) throw Error((partial / "rsvio_demo_sim_config.json").string() + ": cannot write");
  }
  fs::remove_all(data);
  fs::rename(partial, data);
  return false;
}

// "--set a=b --set c=d" -> {"a=b", "c=d"}.
std::vector<std::string> setsOf(const std::string& line) {
  std::istringstream is(line);
  std::vector<std::string> out;
  std::string tok;
  bool next_is_value = false;
  while (is >> tok) {
    if (tok == "--set") {
      next_is_value = true;
      continue;
    }
    if (next_is_value) out.push_back(tok);
    next_is_value = false;
  }
  return out;
}

RunResult runOnce(const std::string& cfg, const std::vector<std::string>& sets, const std::string& data,
                  const std::string& dir, const GlobalOptions& g, PluginHost& host) {
  RunRequest req;
  req.config_path = cfg;
  req.sets = sets;
  req.data_dir = data;
  req.out_dir = dir;
  req.verbosity = g.verbosity;
  RunResult res = runPipeline(req, host);
  printRunWarnings(res.report, "demo");
  renderRunOutputs(dir, g.verbosity);
  return res;
}

std::string ateText(const Report& rep) {
  char b[128];
  if (rep.eval) std::snprintf(b, sizeof b, "%.4f m", rep.eval->ate_rmse_m);
  else std::snprintf(b, sizeof b, "n/a");
  return rep.ok() ? std::string(b) : std::string(b) + " (run failed: " + rep.error + ")";
}

// When the default model is lost part way, its ATE covers only the frames it tracked and the run with
// the named line covers the whole sequence: not comparable. `diagnose --against` also evaluates both
// over the frames both tracked (its "common_span"); the demo prints that line. Returns "" when the first
// run was not lost (nothing to add) or the comparison has nothing.
std::string commonSpanText(const nlohmann::json& cmp) {
  if (!cmp.contains("against") || !cmp["against"].contains("common_span")) return "";
  const auto& c = cmp["against"];
  if (c["before"].value("status", "") == "ok") return "";
  const auto& s = c["common_span"];
  if (s.contains("note")) return "ATE over the common span: not computed (" + s["note"].get<std::string>() + ")";
  std::string align = s["align"].get<std::string>();
  align = align == "sim3" ? "Sim(3)" : align == "se3" ? "SE(3)" : align;
  char b[256];
  std::snprintf(b, sizeof b, "ATE over the span the default model tracked (%d poses, %.2f s, %s): before %.4f m, after %.4f m",
                s["frames_before"].get<int>(), s["to_s"].get<double>() - s["from_s"].get<double>(), align.c_str(),
                s["ate_before_m"].get<double>(), s["ate_after_m"].get<double>());
  return b;
}

int runDemo(const std::string& out, bool fresh, const GlobalOptions& g) {
  const std::string cfg_dir = configDir();
  const std::string sim_cfg = (fs::path(cfg_dir) / "sim" / "demo.json").string();
  const std::string run_cfg = (fs::path(cfg_dir) / "default.json").string();
  for (const auto& p : {sim_cfg, run_cfg})
    if (!fs::exists(p)) throw Error(p + ": demo config not found (set RSVIO_CONFIG_DIR to rsvio's configs/ folder)");
  PluginHost host(PluginHost::defaultSearchPath(g.plugin_path));
  const std::string data = (fs::path(out) / "data").string();
  const std::string before_dir = (fs::path(out) / "default").string();
  const std::string after_dir = (fs::path(out) / "default_fixed").string();

  std::printf("rsvio demo: 1/5 simulating %s into %s\n", sim_cfg.c_str(), data.c_str());
  std::fflush(stdout);
  const auto t0 = std::chrono::steady_clock::now();
  if (prepareData(sim_cfg, data, fresh, host))
    std::printf("  reusing the dataset simulated before from the same config and seed (--reuse-data)\n");
  else
    std::printf("  simulated in %.1f s\n", std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());

  std::printf("rsvio demo: 2/5 running the default model %s\n", run_cfg.c_str());
  printAssembled(loadRunConfig(run_cfg, {}, host));
  std::fflush(stdout);
  RunResult before = runOnce(run_cfg, {}, data, before_dir, g, host);
  const Report& rb = before.report;
  std::printf("  %s, %ld frames, %ld keyframes, %.1f fps (realtime factor %.2f), ATE %s\n", rb.status.c_str(), rb.frames,
              rb.keyframes, rb.fps, rb.realtime_factor, ateText(rb).c_str());
  const std::string not_used = notUsedLine(rb, data, before.effective_config["output"]["evaluate"].get<bool>());
  if (!not_used.empty()) std::printf("  %s\n", not_used.c_str());

  std::printf("rsvio demo: 3/5 diagnosing %s (from its folder alone)\n", before_dir.c_str());
  std::fflush(stdout);
  DiagnoseRequest dq;
  dq.run_dir = before_dir;
  const nlohmann::json d = diagnoseRun(dq, host);
  std::istringstream dtext(formatDiagnosis(d));
  for (std::string l; std::getline(dtext, l);)
    if (l.rfind("figures:", 0) != 0) std::printf("  %s\n", l.c_str());
  const std::string verdict = d["verdict"];
  std::string line;
  nlohmann::json cmp;
  RunResult after;
  bool ran_after = false;
  if (verdict != "none") {
    line = d["config_line"];
    std::printf("rsvio demo: 4/5 running again with the named line: %s\n", line.c_str());
    std::fflush(stdout);
    after = runOnce(run_cfg, setsOf(line), data, after_dir, g, host);
    ran_after = true;
    std::printf("rsvio demo: 5/5 comparing (rsvio diagnose --run %s --against %s)\n", after_dir.c_str(),
                before_dir.c_str());
    std::fflush(stdout);
    DiagnoseRequest aq;
    aq.run_dir = after_dir;
    aq.against = before_dir;
    cmp = diagnoseRun(aq, host);
  } else {
    std::printf("rsvio demo: 4/5 and 5/5 skipped: the diagnosis names no missing effect\n");
  }

  std::printf("\nsequence: %s (hidden: a ~30 ms rolling-shutter readout the calibration does not know)\n", data.c_str());
  std::printf("verdict:  %s\n", verdict.c_str());
  if (!line.empty()) std::printf("added:    %s\n", line.c_str());
  std::printf("ATE before (default model): %s\n", ateText(rb).c_str());
  if (ran_after) {
    std::printf("ATE after  (with the line): %s\n", ateText(after.report).c_str());
    const std::string common = commonSpanText(cmp);
    if (!common.empty()) std::printf("%s\n", common.c_str());
    if (cmp.contains("against") && cmp["against"].contains("evidence_gone"))
      std::printf("evidence of %s after the change: %s\n", verdict.c_str(),
                  cmp["against"]["evidence_gone"].get<bool>() ? "gone" : "still there");
  }
  std::printf("figures:  %s\n", (fs::path(before_dir) / "index.html").string().c_str());
  for (const auto& f : d["figures"])
    if (f.get<std::string>().find("diagnose_" + verdict) != std::string::npos) std::printf("          %s\n", f.get<std::string>().c_str());
  if (ran_after) {
    std::printf("          %s\n", (fs::path(after_dir) / "index.html").string().c_str());
    for (const auto& f : cmp["figures"])
      if (f.get<std::string>().find("against/diagnose_" + verdict) != std::string::npos)
        std::printf("          %s\n", f.get<std::string>().c_str());
  }
  // The demo's job is done when it has told the story, whatever the models made of the sequence: a
  // global-shutter model failing on a hidden rolling shutter is the demo's finding, not its error.
  return 0;
}

}  // namespace

void addDemoCommand(CLI::App& root, const GlobalOptions& g, CommandResult& r) {
  auto* sub = root.add_subcommand("demo", "the main job on a built-in synthetic sequence");
  static std::string out = "out/demo";
  static bool reuse = false;
  sub->add_option("--out", out, "output folder")->capture_default_str();
  sub->add_flag("--reuse-data", reuse,
                "reuse <out>/data when it was simulated from the same config and seed (default: simulate afresh)");
  sub->callback([&g, &r] { r.exit_code = runDemo(out, !reuse, g); });
}

}  // namespace rsvio::app
