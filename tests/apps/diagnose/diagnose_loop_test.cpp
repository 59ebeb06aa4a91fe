// The diagnosis loop on small simulated data (320x256, 3 s, configs/sim/tiny_gs.json with one hidden
// effect): run the model without the effect's plugin, `rsvio diagnose` names the effect from the run
// folder alone, the named config line makes the ATE fall clearly, and the evidence is gone in the new
// run (`diagnose --against`). Clean data with three seeds gives verdict none. Deleting truth.json and the
// ground truth changes neither the estimator's outputs nor the verdict.
// Figures behind the chosen seeds and ratios: plugins/probe/*/README.md and docs/diagnose.md.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>

namespace fs = std::filesystem;

namespace {

std::string bin() {
  const char* b = std::getenv("RSVIO_BIN");
  return b ? std::string(b) : std::string(RSVIO_BINARY_DIR) + "/bin/rsvio";
}

std::string configs() { return std::string(RSVIO_SOURCE_DIR) + "/configs"; }

// Runs `rsvio <args>`, returns exit status; stdout into *out when given.
int rsvio(const std::string& args, std::string* out = nullptr) {
  const std::string cmd = bin() + " " + args + (out ? " 2>/dev/null" : " >/dev/null 2>&1");
  FILE* p = ::popen(cmd.c_str(), "r");
  if (!p) return -1;
  std::string s;
  char buf[4096];
  size_t n;
  while ((n = fread(buf, 1, sizeof buf, p)) > 0) s.append(buf, n);
  const int st = ::pclose(p);
  if (out) *out = s;
  return WEXITSTATUS(st);
}

fs::path workDir(const std::string& name) {
  const fs::path d = fs::path(RSVIO_BINARY_DIR) / "test_out" / "diagnose" / name;
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

const std::string kExposure =
    "'effects.exposure={\"plugin\":\"effect.exposure\",\"params\":{\"amplitude_stops\":0.5,\"period_s\":8.0,"
    "\"jitter_stops\":0.03}}'";
const std::string kVignette = "'effects.vignette={\"plugin\":\"effect.vignette\"}'";
const std::string kTimeOffset =
    "'effects.time_offset={\"plugin\":\"effect.time_offset\",\"params\":{\"offset_ms\":20.0}}'";

void simulate(const fs::path& data, int seed, const std::string& set = "", const std::string& cfg = "tiny_gs.json") {
  ASSERT_EQ(rsvio("simulate --config " + configs() + "/sim/" + cfg + " --out " + data.string() + " --seed " +
                  std::to_string(seed) + (set.empty() ? "" : " --set " + set)),
            0);
}

// rsvio run of `config` (gs_vo unless said) with extra --set lines; returns report.json (status may be
// "failed": exit 1).
nlohmann::json run(const fs::path& data, const fs::path& out, const std::string& sets,
                   const std::string& config = "gs_vo.json") {
  const int rc = rsvio("run --config " + configs() + "/" + config + " --data " + data.string() + " --out " +
                       out.string() + " " + sets);
  EXPECT_TRUE(rc == 0 || rc == 1) << "rsvio run exit " << rc;
  std::ifstream in(out / "report.json");
  return in ? nlohmann::json::parse(in) : nlohmann::json();
}

nlohmann::json diagnose(const fs::path& run_dir, const std::string& extra = "") {
  std::string out;
  EXPECT_EQ(rsvio("diagnose --run " + run_dir.string() + " --json " + extra, &out), 0);
  return nlohmann::json::parse(out);
}

double ate(const nlohmann::json& report) {
  if (report.contains("eval") && report["eval"].contains("ate_rmse_m")) return report["eval"]["ate_rmse_m"];
  return 1e9;  // a run that failed before it could be evaluated counts as a large error
}

std::string readFile(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

void checkContractShape(const nlohmann::json& d) {
  ASSERT_TRUE(d.contains("verdict"));
  ASSERT_TRUE(d.contains("ranking"));
  for (const auto& e : d["ranking"])
    for (const char* k : {"effect", "score", "plugin", "config_line", "statistic", "threshold"})
      EXPECT_TRUE(e.contains(k)) << k;
}

// An exposure ramp during the monocular start (1 stop over a 4 s period, the sine at its steepest:
// 11-47 % brighter between the start's two keyframes): gs_vo without affine brightness ends in its
// first window (4-23 residuals), and the start's corner steps in the diagnostics log are the evidence
// that names exposure. With the named line the run tracks every frame because keyframe 1 starts with
// the corners' gain (backend.init_affine_min_change); without that start it fails as before (the trace
// into keyframe 1 loses its candidates, or the tracker its points). Seeds 3 and 6; on seeds 1-6 the
// start with the gain tracked 5 (all but 2), without it 2 (docs/diagnose.md).
TEST(DiagnoseLoop, AnExposureRampInTheStartIsNamedFromTheStartsCornersAndTheLineTracksThrough) {
  const std::string ramp =
      "'effects.exposure={\"plugin\":\"effect.exposure\",\"params\":{\"amplitude_stops\":1.0,\"period_s\":4.0,"
      "\"jitter_stops\":0.0}}'";
  for (int seed : {3, 6}) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const fs::path dir = workDir("exposure_ramp_" + std::to_string(seed));
    simulate(dir / "data", seed, ramp);
    const nlohmann::json before = run(dir / "data", dir / "before", "--set photometric.affine=null");
    EXPECT_EQ(before.value("status", ""), "failed");
    const nlohmann::json d = diagnose(dir / "before");
    ASSERT_EQ(d["verdict"], "exposure") << d.dump(1);
    EXPECT_GE(d["ranking"][0]["details"].value("start_pairs", 0), 3);
    EXPECT_GE(d["data"].value("start_corner_steps", 0), 3);
    const std::string line = d["config_line"];
    const nlohmann::json after = run(dir / "data", dir / "after", "--set photometric.affine=null " + line);
    EXPECT_EQ(after.value("status", ""), "ok") << after.dump(1);
    EXPECT_EQ(after.value("frames", 0), 57);
    EXPECT_LT(ate(after), 0.05);
    // The before-run has two poses: the error over the frames both tracked cannot be compared, and the
    // comparison says why instead of an ATE of nothing.
    const nlohmann::json cmp = diagnose(dir / "after", "--no-figures --against " + (dir / "before").string());
    EXPECT_NE(cmp["against"]["common_span"].value("note", "").find("at least 3"), std::string::npos)
        << cmp["against"]["common_span"].dump();
    const nlohmann::json no_gain = run(dir / "data", dir / "no_gain",
                                       "--set photometric.affine=null " + line + " --set backend.init_affine_min_change=100");
    EXPECT_EQ(no_gain.value("status", ""), "failed") << "the start's gain is what lets the run through";
  }
}

// The loop for one effect: the diagnosis names `effect` first, its line makes the ATE fall by
// `min_ratio`, the evidence is gone in the new run. With max_rounds > 1 the new run is diagnosed again
// while it names the same effect (a value refined: probe.vignetting after its own fixed polynomial), its
// line appended, and the last run is held against the first.
void loop(const fs::path& dir, const fs::path& data, const std::string& base_sets, const std::string& effect,
          double min_ratio, bool evidence_must_go = true, const std::string& config = "gs_vo.json",
          int max_rounds = 1) {
  const nlohmann::json before = run(data, dir / "before", base_sets, config);
  const nlohmann::json d = diagnose(dir / "before");
  checkContractShape(d);
  ASSERT_EQ(d["verdict"], effect) << d.dump(1);
  ASSERT_EQ(d["ranking"][0]["effect"], effect);
  std::string line = d["config_line"];
  fs::path last = dir / "after";
  nlohmann::json after = run(data, last, base_sets + " " + line, config);
  for (int round = 2; round <= max_rounds; ++round) {
    const nlohmann::json again = diagnose(last, "--no-figures");
    if (again["verdict"] != effect) break;
    line += " " + again["config_line"].get<std::string>();
    last = dir / ("after" + std::to_string(round));
    after = run(data, last, base_sets + " " + line, config);
  }
  EXPECT_EQ(after.value("status", ""), "ok") << after.dump(1);
  EXPECT_GT(ate(before), min_ratio * ate(after)) << "ATE before " << ate(before) << " after " << ate(after)
                                                  << " with " << line;
  const nlohmann::json cmp = diagnose(last, "--against " + (dir / "before").string());
  EXPECT_EQ(cmp["verdict"], "none") << cmp.dump(1);
  EXPECT_EQ(cmp["against"]["before_verdict"], effect);
  ASSERT_TRUE(cmp["against"].contains("evidence_gone"));
  if (evidence_must_go) EXPECT_TRUE(cmp["against"]["evidence_gone"].get<bool>()) << cmp["against"].dump(1);
  // Both runs' error over the frames both tracked: never more of the after-run's poses than frames the
  // before-run saw (its ATE covers only those when it failed).
  const nlohmann::json& span = cmp["against"]["common_span"];
  ASSERT_TRUE(span.contains("ate_before_m") && span.contains("ate_after_m")) << span.dump();
  EXPECT_LE(span["frames_after"].get<int>(), before.value("frames", 0)) << span.dump();
  EXPECT_GE(span["frames_before"].get<int>(), 3);
  // The after-run's page shows the comparison.
  EXPECT_NE(readFile(last / "index.html").find("over the frames both tracked"), std::string::npos);
  // The figures exist and the run page links them.
  ASSERT_FALSE(d["figures"].empty());
  for (const auto& f : d["figures"]) EXPECT_TRUE(fs::exists(f.get<std::string>())) << f;
  const std::string page = readFile(dir / "before" / "index.html");
  EXPECT_NE(page.find("figures/diagnose_" + effect + ".png"), std::string::npos);
}

// Exposure (0.5 stops over 8 s, 0.03 stops per frame), gs_vo without affine brightness, seed 3: measured
// ATE 6.4 mm -> 1.4 mm with the named line (4.5x); asked: 2x.
TEST(DiagnoseLoop, ExposureNamedAndAffineMakesTheErrorFall) {
  const fs::path dir = workDir("exposure");
  simulate(dir / "data", 3, kExposure);
  loop(dir, dir / "data", "--set photometric.affine=null", "exposure", 2.0);

  // Without truth.json and the ground truth: the same estimator outputs and the same verdict.
  fs::copy(dir / "data", dir / "blind", fs::copy_options::recursive);
  fs::remove(dir / "blind" / "truth.json");
  fs::remove_all(dir / "blind" / "mav0" / "state_groundtruth_estimate0");
  fs::remove_all(dir / "blind" / "mav0" / "mocap0");
  ASSERT_FALSE(fs::exists(dir / "blind" / "truth.json"));
  run(dir / "blind", dir / "blind_run", "--set photometric.affine=null");
  for (const char* f : {"trajectory.tum", "keyframes.tum", "diagnostics.bin", "points.ply"})
    EXPECT_EQ(readFile(dir / "before" / f), readFile(dir / "blind_run" / f)) << f << " differs without ground truth";
  const nlohmann::json a = diagnose(dir / "before", "--no-figures");
  const nlohmann::json b = diagnose(dir / "blind_run", "--no-figures");
  EXPECT_EQ(a["verdict"], b["verdict"]);
  EXPECT_EQ(a["ranking"].size(), b["ranking"].size());
  for (size_t i = 0; i < a["ranking"].size() && i < b["ranking"].size(); ++i) {
    EXPECT_EQ(a["ranking"][i]["effect"], b["ranking"][i]["effect"]);
    EXPECT_EQ(a["ranking"][i]["statistic"], b["ranking"][i]["statistic"]);
    EXPECT_EQ(a["ranking"][i]["config_line"], b["ranking"][i]["config_line"]);
  }
}

// Vignetting (corner at half the centre), gs_vo with affine brightness, seed 1: named (statistic 4.6);
// the line starts photometric.vignette in mode estimate from the probe's fit and the run refines it
// online (three refinements): measured ATE 44.6 mm -> 4.7 mm, evidence 4.61 -> 0.63; asked: 2x and the
// evidence gone. A run with a fixed polynomial would be named again for what it left (up to three
// rounds here; plugins/probe/vignetting/README.md). At DSO's keyframe density (backend.kf_flow_scale 1):
// with gs_vo's half density after 7 keyframes the online estimate of this 3 s sequence has fewer residual
// rows (23 keyframes in the run after the line against 33) and the evidence ended at 1.02 against its
// threshold of 1.0 (ATE 36.6 -> 3.7 mm, the verdict none): the test is about the loop, not about how
// fast the estimate converges with fewer keyframes.
TEST(DiagnoseLoop, VignettingNamedAndTheSuggestedPolynomialMakesTheErrorFall) {
  const fs::path dir = workDir("vignetting");
  simulate(dir / "data", 1, kVignette);
  loop(dir, dir / "data", "--set backend.kf_flow_scale=1", "vignetting", 2.0, /*evidence_must_go=*/true, "gs_vo.json",
       /*max_rounds=*/3);
}

// Rolling shutter (tiny_rs.json, 117.88 us per row = 30 ms readout), gs_vo, seed 3: named (|z| 5.3,
// threshold 4), the line (shutter.rolling, 117 us from the frame period) takes the ATE from 55 mm to
// 7.6 mm (7x), evidence 5.3 -> 1.5; asked: 2x. (Seed 1: the next test.)
TEST(DiagnoseLoop, RollingShutterNamedAndTheRollingShutterModelMakesTheErrorFall) {
  const fs::path dir = workDir("rolling_shutter");
  simulate(dir / "data", 3, "", "tiny_rs.json");
  loop(dir, dir / "data", "", "rolling_shutter", 2.0);
}

// Rolling shutter, tiny_rs seed 1, where gs_vo's tracker used to declare the frame lost at frame 16
// (explained ratio 0.11, the frame before 0.27) and the 0.5 s before left the probe too little evidence
// (|z| 3.0 against 4). The tracker keeps a frame whose explained ratio falls gradually
// (frontend.track_explained_keep_fraction, docs/frontend.md "Poorly explained frames"): the run tracks all
// 57 frames (ATE 80 mm), its report warns of the poorly explained frames, and the probe names the rolling
// shutter (|z| 6.7). With the rule off the run fails at frame 16 as before and nothing is named, but
// the failed run's rolling-shutter probe is 0.75 of the way to its threshold: the diagnosis gives it as
// a lead to test (not a verdict), and its line tracks the sequence. Clean runs that end ok never get one.
TEST(DiagnoseLoop, RollingShutterNamedWhereTheGlobalShutterModelExplainsTheFramesLessAndLess) {
  const fs::path dir = workDir("rolling_shutter_kept");
  simulate(dir / "data", 1, "", "tiny_rs.json");
  const nlohmann::json kept = run(dir / "data", dir / "kept", "");
  EXPECT_EQ(kept["status"], "ok");
  EXPECT_NE(kept["warnings"].dump().find("explained ratio below"), std::string::npos) << kept["warnings"].dump();
  EXPECT_EQ(diagnose(dir / "kept", "--no-figures")["verdict"], "rolling_shutter");
  const nlohmann::json lost = run(dir / "data", dir / "lost", "--set frontend.track_explained_keep_fraction=0");
  EXPECT_EQ(lost["status"], "failed");
  const nlohmann::json d = diagnose(dir / "lost", "--no-figures");
  EXPECT_EQ(d["verdict"], "none");
  ASSERT_TRUE(d.contains("lead")) << d.dump(1);
  EXPECT_EQ(d["lead"]["effect"], "rolling_shutter");
  EXPECT_FALSE(d.contains("config_line")) << "a lead is not a verdict";
  const nlohmann::json tested = run(dir / "data", dir / "lead",
                                    "--set frontend.track_explained_keep_fraction=0 " + d["lead"]["config_line"].get<std::string>());
  EXPECT_EQ(tested["status"], "ok") << tested.dump(1);
  // The same log from a run that ended ok: nothing stands out, no lead.
  fs::copy(dir / "lost", dir / "lost_ok", fs::copy_options::recursive);
  nlohmann::json rep = lost;
  rep["status"] = "ok";
  std::ofstream(dir / "lost_ok" / "report.json") << rep.dump();
  EXPECT_FALSE(diagnose(dir / "lost_ok", "--no-figures").contains("lead")) << "an ok run gets no lead";
}

// Camera-IMU time offset (the image stamped t_cam is captured at IMU time t_cam + 20 ms), starting from
// configs/default.json (visual-inertial, offset not estimated), seed 1: named (|z| 15.2, a shift
// explains 78 % of the misfit, estimate 19.8 ms), the line (imu.time_offset_correction_ms=19.8 and
// imu.estimate_time_offset=true) takes the ATE from 113 mm to 5.1 mm (22x; final offset 20.26 ms),
// evidence 2.53 -> 0.04; asked: 2x. The probe reads the dataset's IMU and the run's trajectory, not the
// diagnostics log; without truth.json and ground truth it gives the same statistic.
TEST(DiagnoseLoop, TimeOffsetNamedAndEstimatingItMakesTheErrorFall) {
  const fs::path dir = workDir("time_offset");
  simulate(dir / "data", 1, kTimeOffset);
  loop(dir, dir / "data", "", "time_offset", 2.0, true, "default.json");
  const nlohmann::json d = diagnose(dir / "before", "--no-figures");
  ASSERT_EQ(d["ranking"][0]["effect"], "time_offset");
  const double est = d["ranking"][0]["details"]["offset_estimate_ms"];
  EXPECT_NEAR(est, 20.0, 4.0) << "the probe's estimate of the missing offset";
  fs::copy(dir / "data", dir / "blind", fs::copy_options::recursive);
  fs::remove(dir / "blind" / "truth.json");
  fs::remove_all(dir / "blind" / "mav0" / "state_groundtruth_estimate0");
  fs::remove_all(dir / "blind" / "mav0" / "mocap0");
  run(dir / "blind", dir / "blind_run", "", "default.json");
  const nlohmann::json b = diagnose(dir / "blind_run", "--no-figures");
  EXPECT_EQ(b["ranking"][0]["effect"], "time_offset");
  EXPECT_EQ(b["ranking"][0]["statistic"], d["ranking"][0]["statistic"]);
}

// Two hidden effects (exposure and a 20 ms time offset), from configs/default.json, seed 1: the loop
// runs twice. Measured: exposure first (the line adds photometric.affine: 27.9 -> 18.4 mm), then the
// time offset (19.8 ms measured: 18.4 -> 6.3 mm), then none. Asked: each effect named once, in either
// order, the final verdict none, and the ATE 2x lower at the end.
TEST(DiagnoseLoop, TwoHiddenEffectsAreNamedOneAfterTheOther) {
  const fs::path dir = workDir("two_effects");
  simulate(dir / "data", 1, kExposure + " --set " + kTimeOffset);
  std::string sets;
  std::set<std::string> named;
  const nlohmann::json first = run(dir / "data", dir / "run0", sets, "default.json");
  for (int step = 0; step < 2; ++step) {
    const nlohmann::json d = diagnose(dir / ("run" + std::to_string(step)), "--no-figures");
    ASSERT_NE(d["verdict"], "none") << "step " << step << ": " << d.dump(1);
    const std::string effect = d["verdict"];
    EXPECT_TRUE(effect == "exposure" || effect == "time_offset") << effect;
    EXPECT_TRUE(named.insert(effect).second) << effect << " named twice";
    sets += " " + d["config_line"].get<std::string>();
    run(dir / "data", dir / ("run" + std::to_string(step + 1)), sets, "default.json");
  }
  const nlohmann::json d = diagnose(dir / "run2", "--no-figures");
  EXPECT_EQ(d["verdict"], "none") << d.dump(1);
  std::ifstream in(dir / "run2" / "report.json");
  const nlohmann::json last = nlohmann::json::parse(in);
  EXPECT_GT(ate(first), 2.0 * ate(last)) << "ATE first " << ate(first) << " last " << ate(last) << " with" << sets;
}

// The time-offset probe on clean visual-inertial runs (default.json, seeds 1 and 3: |z| 1.3 and 0.1),
// and not applicable to visual odometry (the IMU does not enter its model) or to a run that estimates
// the offset.
TEST(DiagnoseLoop, TimeOffsetProbeStaysQuietOnCleanDataAndIsNotApplicableWithoutTheImu) {
  const fs::path dir = workDir("time_offset_clean");
  for (int seed : {1, 3}) {
    const fs::path data = dir / ("data" + std::to_string(seed));
    simulate(data, seed);
    const fs::path out = dir / ("run" + std::to_string(seed));
    run(data, out, "", "default.json");
    const nlohmann::json d = diagnose(out, "--no-figures");
    EXPECT_EQ(d["verdict"], "none") << "seed " << seed << ": " << d.dump(1);
    bool tested = false;
    for (const auto& e : d["ranking"])
      if (e["effect"] == "time_offset") {
        tested = true;
        EXPECT_LT(e["score"].get<double>(), 1.0) << e.dump(1);
      }
    EXPECT_TRUE(tested) << d.dump(1);
  }
  auto notApplicable = [](const nlohmann::json& d) {
    for (const auto& e : d["not_applicable"])
      if (e["effect"] == "time_offset") return true;
    return false;
  };
  run(dir / "data1", dir / "vo", "", "gs_vo.json");
  EXPECT_TRUE(notApplicable(diagnose(dir / "vo", "--no-figures")));
  run(dir / "data1", dir / "estimated", "--set imu.estimate_time_offset=true", "default.json");
  EXPECT_TRUE(notApplicable(diagnose(dir / "estimated", "--no-figures")));
}

// Clean data, three seeds, gs_vo with and without affine brightness: verdict none.
TEST(DiagnoseLoop, CleanDataGivesNone) {
  const fs::path dir = workDir("clean");
  for (int seed : {1, 3, 4}) {
    const fs::path data = dir / ("data" + std::to_string(seed));
    simulate(data, seed);
    for (const std::string sets : {"", "--set photometric.affine=null"}) {
      const fs::path out = dir / ("run" + std::to_string(seed) + (sets.empty() ? "_affine" : "_noaffine"));
      run(data, out, sets);
      const nlohmann::json d = diagnose(out, "--no-figures");
      checkContractShape(d);
      EXPECT_EQ(d["verdict"], "none") << "seed " << seed << " " << sets << ": " << d.dump(1);
    }
  }
}

// A run that fails part way is diagnosed from what it wrote, and says how much data it had.
TEST(DiagnoseLoop, FailedRunIsDiagnosedAndSaysHowMuchDataItHad) {
  const fs::path dir = workDir("failed");
  // Vignetting, seed 5: gs_vo loses track before the end (measured 2026-12-06: at frame 56 of 57, with
  // and without the small-step stop). Which seed fails moves with the rounding of the bundle
  // adjustment: seed 3, used before, failed at frame 51 until the global-shutter host blocks came from
  // the target's (docs/performance.md); of seeds 1-8 only 5 fails now.
  simulate(dir / "data", 5, kVignette);
  const nlohmann::json rep = run(dir / "data", dir / "run", "");
  ASSERT_EQ(rep.value("status", ""), "failed") << rep.dump(1);
  std::string text;
  ASSERT_EQ(rsvio("diagnose --run " + (dir / "run").string(), &text), 0);
  EXPECT_NE(text.find("failed"), std::string::npos) << text;
  EXPECT_NE(text.find("frame pairs"), std::string::npos) << text;
  const nlohmann::json d = diagnose(dir / "run", "--no-figures");
  EXPECT_GT(d["data"]["usable_observations"].get<long>(), 0);
  EXPECT_EQ(d["run_status"]["status"], "failed");
  EXPECT_EQ(d["verdict"], "vignetting") << d.dump(1);
}

TEST(DiagnoseLoop, MissingRunFolderIsABadInput) {
  std::string out;
  EXPECT_EQ(rsvio("diagnose --run /nonexistent/run --json", &out), 2);
}

}  // namespace
