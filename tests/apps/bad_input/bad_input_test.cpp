// The bad-input corpus: what a new user feeds rsvio by mistake (broken datasets, calibrations, configs
// and --set values, trajectories for eval, run folders for render and diagnose, output paths that
// cannot be written), each through the real CLI binary ($RSVIO_BIN: the sanitizer build runs its own).
// Every case asserts the user contract for bad input:
//   - exit code non-zero and below 128 (no crash, no abort, no sanitizer report: those end in a signal
//     or in ASan's exit code with a multi-line report);
//   - stderr holds exactly one non-empty line, and it names the file (or option) and the line or key;
//   - nothing claims success: no "run ok" on stdout and no report.json saying "ok" anywhere under the
//     case's folder.
// One table; each row builds its inputs in a fresh folder (a valid 64x48, 5-frame EuRoC dataset, a
// valid run folder) and breaks one thing.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "plugins/source/source_fixture.h"

namespace fs = std::filesystem;

namespace {

using rsvio::test::DatasetSpec;
using rsvio::test::readText;
using rsvio::test::writeText;

std::string quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

std::string rsvioBin() {
  const char* b = std::getenv("RSVIO_BIN");
  return b ? b : std::string(RSVIO_BINARY_DIR) + "/bin/rsvio";
}

const std::string kSrc = RSVIO_SOURCE_DIR;

// The inputs of one case: a folder with a valid dataset (data/), a valid run folder (run/), a valid
// trajectory pair (gt.tum, est.tum) and a config (cfg.json extending the repository's gs_vo.json).
struct Case {
  fs::path dir;
  fs::path data() const { return dir / "data"; }
  fs::path mav0() const { return dir / "data" / "mav0"; }
  fs::path cam() const { return dir / "data" / "mav0" / "cam0"; }
  fs::path imu() const { return dir / "data" / "mav0" / "imu0"; }
  fs::path out() const { return dir / "out"; }
  fs::path run() const { return dir / "run"; }
  std::string p(const std::string& rel) const { return (dir / rel).string(); }
  void put(const std::string& rel, const std::string& text) const { writeText(dir / rel, text); }
  // Replaces the first `from` in a file (the case is wrong when it is absent).
  void edit(const std::string& rel, const std::string& from, const std::string& to) const {
    std::string s = readText(dir / rel);
    const size_t at = s.find(from);
    if (at == std::string::npos) throw std::runtime_error("case setup: '" + from + "' not in " + rel);
    s.replace(at, from.size(), to);
    writeText(dir / rel, s);
  }
  std::string firstImage() const {
    std::vector<fs::path> v;
    for (const auto& e : fs::directory_iterator(cam() / "data")) v.push_back(e.path());
    std::sort(v.begin(), v.end());
    return v.front().string();
  }
  // `rsvio run` on data/ into out/ with the case's config.
  std::string runArgs(const std::string& extra = "") const {
    return "run --config " + quote(p("cfg.json")) + " --data " + quote(data().string()) + " --out " +
           quote(out().string()) + (extra.empty() ? "" : " " + extra);
  }
};

struct BadInput {
  const char* name;
  const char* category;
  std::function<std::string(const Case&)> setup;  // breaks one thing, returns the CLI arguments
  std::vector<std::string> expect;                // substrings of the stderr line ({dir} = the case's folder)
  int code = 2;                                   // expected exit code (0: any in [1, 127])
};

std::string tum(int n, double t0 = 100.0, bool header = true) {
  std::string s = header ? "# frame: camera\n" : "";
  for (int i = 0; i < n; ++i) {
    char b[200];
    std::snprintf(b, sizeof(b), "%.9f %.6f %.6f 0.5 0 0 %.6f %.6f\n", t0 + 0.05 * i, 0.1 * i, 0.02 * i * i,
                  std::sin(0.02 * i), std::cos(0.02 * i));
    s += b;
  }
  return s;
}

void writeValidRun(const fs::path& run) {
  writeText(run / "trajectory.tum", tum(12));
  writeText(run / "keyframes.tum", tum(4));
  writeText(run / "states.csv", "# t_ns,v_x,v_y,v_z,bg_x,bg_y,bg_z,ba_x,ba_y,ba_z,xi_tx,xi_ty,xi_tz,xi_rx,xi_ry,xi_rz,scale,time_offset_ms,line_delay_us\n");
  writeText(run / "points.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                                "property float z\nproperty float intensity\nend_header\n0 0 1 100\n");
  writeText(run / "config.json", "{}\n");
  writeText(run / "report.json", R"({"status": "failed", "error": "tracking lost", "frames": 12, "keyframes": 4})");
}

std::vector<BadInput> corpus() {
  std::vector<BadInput> v;
  auto add = [&](const char* name, const char* cat, std::function<std::string(const Case&)> f,
                 std::vector<std::string> expect, int code = 2) { v.push_back({name, cat, std::move(f), std::move(expect), code}); };

  // ---- datasets ----------------------------------------------------------------------------------
  add("data_folder_missing", "dataset", [](const Case& c) { fs::remove_all(c.data()); return c.runArgs(); },
      {"{dir}/data", "dataset folder not found"});
  add("data_folder_empty", "dataset", [](const Case& c) { fs::remove_all(c.data()); fs::create_directories(c.data()); return c.runArgs(); },
      {"{dir}/data", "folder is empty"});
  add("no_mav0", "dataset", [](const Case& c) { fs::rename(c.mav0(), c.dir / "data" / "MAV0"); return c.runArgs(); },
      {"{dir}/data", "no mav0/"});
  add("image_index_missing", "dataset", [](const Case& c) { fs::remove(c.cam() / "data.csv"); return c.runArgs(); },
      {"cam0/data.csv", "image index not found"});
  add("image_index_empty", "dataset", [](const Case& c) { c.put("data/mav0/cam0/data.csv", ""); return c.runArgs(); },
      {"cam0/data.csv"});
  add("image_index_wrong_columns", "dataset", [](const Case& c) {
        c.edit("data/mav0/cam0/data.csv", ".png\n", ".png,extra\n");
        return c.runArgs(); }, {"cam0/data.csv:2", "expected 2 fields"});
  add("image_index_non_integer_stamp", "dataset", [](const Case& c) {
        c.edit("data/mav0/cam0/data.csv", "\n1000050000000,", "\n1000050000000.5,");
        return c.runArgs(); }, {"cam0/data.csv:3"});
  add("image_index_decreasing_stamp", "dataset", [](const Case& c) {
        c.edit("data/mav0/cam0/data.csv", "\n1000100000000,", "\n999000000000,");
        return c.runArgs(); }, {"cam0/data.csv:4"});
  add("image_index_binary_junk", "dataset", [](const Case& c) {
        c.edit("data/mav0/cam0/data.csv", "\n1000050000000,", std::string("\n\x01\xff\xfe junk,"));
        return c.runArgs(); }, {"cam0/data.csv:3"});
  add("image_missing", "dataset", [](const Case& c) { fs::remove(c.firstImage()); return c.runArgs(); },
      {"1000000000000.png"});
  add("image_not_png", "dataset", [](const Case& c) { writeText(c.firstImage(), "this is text, not an image\n"); return c.runArgs(); },
      {"1000000000000.png"});
  add("image_empty_file", "dataset", [](const Case& c) { writeText(c.firstImage(), ""); return c.runArgs(); },
      {"1000000000000.png"});
  add("image_truncated_png", "dataset", [](const Case& c) {
        const std::string s = readText(c.firstImage());
        writeText(c.firstImage(), s.substr(0, s.size() / 2));
        return c.runArgs(); }, {"1000000000000.png"});
  add("image_wrong_size", "dataset", [](const Case& c) {
        c.edit("data/mav0/cam0/sensor.yaml", "resolution: [64, 48]", "resolution: [80, 48]");
        return c.runArgs(); }, {"1000000000000.png", "64x48"});
  add("calibration_missing", "calibration", [](const Case& c) { fs::remove(c.cam() / "sensor.yaml"); return c.runArgs(); },
      {"{dir}/data", "calibration"});
  add("calibration_bad_yaml", "calibration", [](const Case& c) {
        c.edit("data/mav0/cam0/sensor.yaml", "rate_hz: 20\n", "rate_hz: [20\n");
        return c.runArgs(); }, {"cam0/sensor.yaml:"});
  add("calibration_intrinsics_count", "calibration", [](const Case& c) {
        c.edit("data/mav0/cam0/sensor.yaml", "intrinsics: [45.8654, 45.7296, 31.7215, 23.8375]", "intrinsics: [45.8654, 45.7296, 31.7215]");
        return c.runArgs(); }, {"cam0/sensor.yaml:", "intrinsics"});
  add("calibration_negative_focal", "calibration", [](const Case& c) {
        c.edit("data/mav0/cam0/sensor.yaml", "intrinsics: [45.8654", "intrinsics: [-45.8654");
        return c.runArgs(); }, {"cam0/sensor.yaml:", "intrinsics"});
  add("calibration_unknown_model", "calibration", [](const Case& c) {
        c.edit("data/mav0/cam0/sensor.yaml", "camera_model: pinhole", "camera_model: fisheye9000");
        return c.runArgs(); }, {"cam0/sensor.yaml:", "camera_model"});
  add("calibration_unknown_distortion", "calibration", [](const Case& c) {
        c.edit("data/mav0/cam0/sensor.yaml", "distortion_model: radial-tangential", "distortion_model: spline");
        return c.runArgs(); }, {"cam0/sensor.yaml:", "distortion_model"});
  add("calibration_T_BS_not_4x4", "calibration", [](const Case& c) {
        c.edit("data/mav0/cam0/sensor.yaml", "         0.0, 0.0, 0.0, 1.0]", "         0.0, 0.0, 0.0]");
        return c.runArgs(); }, {"cam0/sensor.yaml:", "T_BS"});
  add("calibration_nan_intrinsic", "calibration", [](const Case& c) {
        c.edit("data/mav0/cam0/sensor.yaml", "31.7215, 23.8375]", ".nan, 23.8375]");
        return c.runArgs(); }, {"cam0/sensor.yaml:", "intrinsics"});
  add("imu_non_numeric", "dataset", [](const Case& c) {
        c.edit("data/mav0/imu0/data.csv", ",0.1,0.2,9.81\n", ",0.1,abc,9.81\n");
        return c.runArgs(); }, {"imu0/data.csv:2:", "abc"});
  add("imu_truncated_row_in_the_middle", "dataset", [](const Case& c) {
        c.edit("data/mav0/imu0/data.csv", ",0.1,0.2,9.81\n", ",0.1\n");
        return c.runArgs(); }, {"imu0/data.csv:2"});
  add("imu_decreasing_stamp", "dataset", [](const Case& c) {
        c.edit("data/mav0/imu0/data.csv", "\n999905000000,", "\n999800000000,");
        return c.runArgs(); }, {"imu0/data.csv:3"});
  add("imu_negative_noise", "calibration", [](const Case& c) {
        c.edit("data/mav0/imu0/sensor.yaml", "gyroscope_noise_density: 1.6968e-04", "gyroscope_noise_density: -1.6968e-04");
        return c.runArgs(); }, {"imu0/sensor.yaml:", "gyroscope_noise_density"});
  add("kalibr_no_cam0", "calibration", [](const Case& c) {
        fs::remove(c.cam() / "sensor.yaml");
        c.put("data/camchain-imucam.yaml", "cam1:\n  camera_model: pinhole\n  intrinsics: [45, 45, 31.5, 23.5]\n  resolution: [64, 48]\n");
        return c.runArgs(); }, {"camchain-imucam.yaml", "cam0"});
  add("kalibr_unsupported_model", "calibration", [](const Case& c) {
        fs::remove(c.cam() / "sensor.yaml");
        c.put("data/camchain-imucam.yaml", "cam0:\n  camera_model: omni\n  intrinsics: [0.8, 45, 45, 31.5, 23.5]\n  resolution: [64, 48]\n");
        return c.runArgs(); }, {"camchain-imucam.yaml:2:", "camera_model"});
  add("pcalib_wrong_count", "calibration", [](const Case& c) {
        c.put("data/mav0/cam0/pcalib.txt", "0 1 2 3\n");
        return c.runArgs(); }, {"cam0/pcalib.txt"});
  add("pcalib_not_increasing", "calibration", [](const Case& c) {
        std::string s;
        for (int k = 0; k < 256; ++k) s += std::to_string(k == 100 ? 50 : k) + " ";
        c.put("data/mav0/cam0/pcalib.txt", s + "\n");
        return c.runArgs(); }, {"cam0/pcalib.txt"});
  add("vignette_not_an_image", "calibration", [](const Case& c) {
        c.put("data/mav0/cam0/vignette.png", "not a png");
        return c.runArgs(); }, {"cam0/vignette.png"});
  add("times_negative_exposure", "calibration", [](const Case& c) {
        c.put("data/mav0/cam0/times.txt", "1000000000000 1000.0 -5\n1000050000000 1000.05 10\n");
        return c.runArgs(); }, {"cam0/times.txt:1"});
  add("times_bad_time", "calibration", [](const Case& c) {
        c.put("data/mav0/cam0/times.txt", "1000000000000 1000.0 5\n1000050000000 soon 10\n");
        return c.runArgs(); }, {"cam0/times.txt:2"});

  // ---- configs and --set -------------------------------------------------------------------------
  add("config_missing", "config", [](const Case& c) { fs::remove(c.dir / "cfg.json"); return c.runArgs(); },
      {"cfg.json"});
  add("config_malformed_json", "config", [](const Case& c) { c.put("cfg.json", "{\n  \"threads\": 1,\n  oops\n}\n"); return c.runArgs(); },
      {"cfg.json:3"});
  add("config_empty_file", "config", [](const Case& c) { c.put("cfg.json", ""); return c.runArgs(); }, {"cfg.json"});
  add("config_not_an_object", "config", [](const Case& c) { c.put("cfg.json", "[1, 2, 3]\n"); return c.runArgs(); },
      {"cfg.json"});
  add("config_unknown_key", "config", [](const Case& c) {
        c.put("cfg.json", "{\"extends\": \"" + kSrc + "/configs/gs_vo.json\", \"fronted\": {}}");
        return c.runArgs(); }, {"fronted"});
  add("config_unknown_plugin", "config", [](const Case& c) {
        c.put("cfg.json", "{\"extends\": \"" + kSrc + "/configs/gs_vo.json\", \"camera\": {\"plugin\": \"camera.pinhol\"}}");
        return c.runArgs(); }, {"camera.pinhol"});
  add("config_wrong_type", "config", [](const Case& c) {
        c.put("cfg.json", "{\"extends\": \"" + kSrc + "/configs/gs_vo.json\", \"threads\": \"two\"}");
        return c.runArgs(); }, {"threads"});
  add("config_out_of_range", "config", [](const Case& c) {
        c.put("cfg.json", "{\"extends\": \"" + kSrc + "/configs/gs_vo.json\", \"threads\": 0}");
        return c.runArgs(); }, {"threads", "[1, 64]"});
  add("config_extends_missing", "config", [](const Case& c) {
        c.put("cfg.json", "{\"extends\": \"nowhere.json\"}");
        return c.runArgs(); }, {"nowhere.json"});
  add("config_extends_cycle", "config", [](const Case& c) {
        c.put("cfg.json", "{\"extends\": \"cfg2.json\"}");
        c.put("cfg2.json", "{\"extends\": \"cfg.json\"}");
        return c.runArgs(); }, {"cfg.json", "cycle"});
  add("config_unknown_plugin_param", "config", [](const Case& c) {
        c.put("cfg.json", "{\"extends\": \"" + kSrc + "/configs/gs_vo.json\", \"solver\": {\"plugin\": \"solver.dense\", \"params\": {\"tolerance_x\": 1}}}");
        return c.runArgs(); }, {"tolerance_x"});
  add("set_without_equals", "set", [](const Case& c) { return c.runArgs("--set threads"); }, {"threads", "="});
  add("set_empty_path", "set", [](const Case& c) { return c.runArgs("--set =3"); }, {"=3"});
  add("set_unknown_key", "set", [](const Case& c) { return c.runArgs("--set frontend.pointz=100"); }, {"frontend.pointz"});
  add("set_null_on_missing_key", "set", [](const Case& c) { return c.runArgs("--set frontend.nothing=null"); },
      {"frontend.nothing"});
  add("set_wrong_type", "set", [](const Case& c) { return c.runArgs("--set threads=abc"); }, {"threads"});
  add("set_out_of_range", "set", [](const Case& c) { return c.runArgs("--set threads=1000"); }, {"threads"});
  add("set_unknown_plugin", "set", [](const Case& c) { return c.runArgs("--set solver.plugin=solver.magic"); },
      {"solver.magic"});
  add("seed_not_a_number", "set", [](const Case& c) { return c.runArgs("--seed abc"); }, {"--seed"});

  // ---- trajectories for eval ---------------------------------------------------------------------
  auto evalArgs = [](const Case& c) {
    return "eval --gt " + quote(c.p("gt.tum")) + " --est " + quote(c.p("est.tum"));
  };
  add("eval_est_missing", "trajectory", [=](const Case& c) { fs::remove(c.dir / "est.tum"); return evalArgs(c); },
      {"est.tum"});
  add("eval_gt_missing", "trajectory", [=](const Case& c) { fs::remove(c.dir / "gt.tum"); return evalArgs(c); },
      {"gt.tum"});
  add("eval_est_empty", "trajectory", [=](const Case& c) { c.put("est.tum", ""); return evalArgs(c); }, {"est.tum"});
  add("eval_est_non_numeric", "trajectory", [=](const Case& c) { c.edit("est.tum", "0.500000", "zero"); return evalArgs(c); },
      {"est.tum:7", "tx", "zero"});
  add("eval_est_wrong_columns", "trajectory", [=](const Case& c) {
        c.put("est.tum", tum(3) + "100.5 1 2 3\n" + tum(3, 101.0, false));
        return evalArgs(c); }, {"est.tum:5"});
  add("eval_est_zero_quaternion", "trajectory", [=](const Case& c) {
        c.put("est.tum", tum(3) + "100.5 1 2 3 0 0 0 0\n");
        return evalArgs(c); }, {"est.tum:5"});
  add("eval_est_nan", "trajectory", [=](const Case& c) {
        c.put("est.tum", tum(3) + "100.5 nan 2 3 0 0 0 1\n");
        return evalArgs(c); }, {"est.tum:5"});
  add("eval_est_no_overlap", "trajectory", [=](const Case& c) { c.put("est.tum", tum(12, 5000.0)); return evalArgs(c); },
      {"est.tum"});
  add("eval_gt_malformed_euroc", "trajectory", [](const Case& c) {
        c.put("gt.csv", "#timestamp,x,y,z,qw,qx,qy,qz\n100000000000,0,0,0,1,0,0\n");
        return "eval --gt " + quote(c.p("gt.csv")) + " --est " + quote(c.p("est.tum")); }, {"gt.csv:2"});
  add("eval_bad_align", "trajectory", [=](const Case& c) { return evalArgs(c) + " --align sim4"; }, {"--align"});
  add("eval_data_without_ground_truth", "trajectory", [](const Case& c) {
        return "eval --data " + quote(c.data().string()) + " --est " + quote(c.p("est.tum")); }, {"{dir}/data"});

  // ---- run folders for render and diagnose -------------------------------------------------------
  add("render_run_missing", "run folder", [](const Case& c) { return "render --no-3d --run " + quote(c.p("nope")); },
      {"{dir}/nope"});
  add("render_run_is_a_file", "run folder", [](const Case& c) { c.put("afile", "x"); return "render --no-3d --run " + quote(c.p("afile")); },
      {"{dir}/afile"});
  add("diagnose_run_missing", "run folder", [](const Case& c) { return "diagnose --run " + quote(c.p("nope")); },
      {"{dir}/nope"}, 0);
  add("diagnose_no_diagnostics_log", "run folder", [](const Case& c) { return "diagnose --no-figures --run " + quote(c.run().string()); },
      {"{dir}/run"}, 0);
  add("diagnose_corrupt_diagnostics_log", "run folder", [](const Case& c) {
        c.put("run/diagnostics.bin", "RSVIODG1 but then garbage");
        return "diagnose --no-figures --run " + quote(c.run().string()); }, {"diagnostics.bin"}, 0);

  // ---- output paths that cannot be written -------------------------------------------------------
  add("run_out_is_a_file", "output", [](const Case& c) { c.put("out", "x"); return c.runArgs(); }, {"{dir}/out"});
  add("run_out_under_a_file", "output", [](const Case& c) {
        c.put("afile", "x");
        return "run --config " + quote(c.p("cfg.json")) + " --data " + quote(c.data().string()) + " --out " + quote(c.p("afile/out")); },
      {"{dir}/afile/out"});
  add("run_out_in_proc", "output", [](const Case& c) {
        return "run --config " + quote(c.p("cfg.json")) + " --data " + quote(c.data().string()) + " --out /proc/rsvio_cannot_be_here"; },
      {"/proc/rsvio_cannot_be_here"});
  add("simulate_out_under_a_file", "output", [](const Case& c) {
        c.put("afile", "x");
        return "-q simulate --config " + quote(kSrc + "/configs/sim/tiny_gs.json") + " --out " + quote(c.p("afile/sim")); },
      {"{dir}/afile/sim"});
  add("simulate_bad_set", "set", [](const Case& c) {
        return "simulate --config " + quote(kSrc + "/configs/sim/tiny_gs.json") + " --out " + quote(c.p("sim")) +
               " --set motion.duration_z=3"; }, {"motion.duration_z"});
  add("eval_out_under_a_file", "output", [=](const Case& c) { c.put("afile", "x"); return evalArgs(c) + " --out " + quote(c.p("afile/ev")); },
      {"{dir}/afile/ev"});
  add("compare_out_under_a_file", "output", [](const Case& c) {
        c.put("afile", "x");
        return "compare --configs " + quote(c.p("cfg.json")) + " --data " + quote(c.data().string()) + " --out " + quote(c.p("afile/cmp")); },
      {"{dir}/afile/cmp"});
  add("compare_config_missing", "config", [](const Case& c) {
        return "compare --configs " + quote(c.p("none.json")) + " --data " + quote(c.data().string()) + " --out " + quote(c.p("cmp")); },
      {"none.json"});
  add("compare_bad_set", "set", [](const Case& c) {
        return "compare --configs " + quote(c.p("cfg.json")) + " --data " + quote(c.data().string()) + " --out " + quote(c.p("cmp")) +
               " --set threads"; }, {"threads"});
  add("render_out_under_a_file", "output", [](const Case& c) {
        c.put("afile", "x");
        return "render --no-3d --run " + quote(c.run().string()) + " --out " + quote(c.p("afile/fig")); }, {"{dir}/afile/fig"},
      0);  // render says "render incomplete" and exits 1 (not 2) for an output folder it cannot create
  return v;
}

class BadInputCli : public ::testing::TestWithParam<BadInput> {};

// gtest prints a failing parameter with this (found by argument-dependent lookup).
void PrintTo(const BadInput& b, std::ostream* os) { *os << b.name << " (" << b.category << ")"; }

std::string replaceAll(std::string s, const std::string& from, const std::string& to) {
  for (size_t at = 0; (at = s.find(from, at)) != std::string::npos; at += to.size()) s.replace(at, from.size(), to);
  return s;
}

// Every report.json under `root` that says "ok".
std::vector<std::string> okReports(const fs::path& root) {
  std::vector<std::string> found;
  std::error_code ec;
  for (auto it = fs::recursive_directory_iterator(root, ec); it != fs::recursive_directory_iterator(); it.increment(ec)) {
    if (ec) break;
    if (it->path().filename() != "report.json") continue;
    const auto j = nlohmann::json::parse(readText(it->path()), nullptr, false);
    if (!j.is_discarded() && j.is_object() && j.value("status", "") == "ok") found.push_back(it->path().string());
  }
  return found;
}

TEST_P(BadInputCli, RefusedWithOneLineNamingTheFileAndNothingClaimsSuccess) {
  const BadInput& bi = GetParam();
  Case c;
  c.dir = fs::temp_directory_path() / ("rsvio_bad_" + std::to_string(::getpid()) + "_" + bi.name);
  fs::remove_all(c.dir);
  DatasetSpec spec;
  rsvio::test::writeDataset(c.data(), spec);
  writeValidRun(c.run());
  c.put("gt.tum", tum(20));
  c.put("est.tum", tum(20));
  c.put("cfg.json", "{\"extends\": \"" + kSrc + "/configs/gs_vo.json\", \"output\": {\"render\": false}}");
  std::string args;
  ASSERT_NO_THROW(args = bi.setup(c)) << bi.name;
  const std::string o = (c.dir / "stdout.txt").string(), e = (c.dir / "stderr.txt").string();
  const int st = std::system((quote(rsvioBin()) + " " + args + " > " + quote(o) + " 2> " + quote(e)).c_str());
  const std::string out = readText(o), err = readText(e);
  const std::string ctx = std::string(bi.name) + ": rsvio " + args + "\n--- stdout:\n" + out + "--- stderr:\n" + err;
  ASSERT_TRUE(WIFEXITED(st)) << "ended by a signal: " << ctx;
  const int code = WEXITSTATUS(st);
  EXPECT_GT(code, 0) << ctx;
  EXPECT_LT(code, 128) << ctx;
  if (bi.code != 0) EXPECT_EQ(code, bi.code) << ctx;
  std::vector<std::string> lines;
  std::istringstream ls(err);
  // rsvio's image reader prints nothing of libpng's or libjpeg's own (rsvio/io/image_file.h): every line counts.
  for (std::string l; std::getline(ls, l);)
    if (!l.empty()) lines.push_back(l);
  ASSERT_EQ(lines.size(), 1u) << "stderr must hold exactly one line: " << ctx;
  for (const auto& x : bi.expect) {
    const std::string want = replaceAll(x, "{dir}", c.dir.string());
    EXPECT_NE(lines[0].find(want), std::string::npos) << "'" << want << "' not named: " << ctx;
  }
  EXPECT_EQ(out.find("run ok"), std::string::npos) << ctx;
  const auto ok = okReports(c.dir);
  EXPECT_TRUE(ok.empty()) << "a report.json says ok: " << ok.front() << "\n" << ctx;
  std::error_code ec;
  fs::remove_all(c.dir, ec);
}

INSTANTIATE_TEST_SUITE_P(Corpus, BadInputCli, ::testing::ValuesIn(corpus()),
                         [](const ::testing::TestParamInfo<BadInput>& i) { return std::string(i.param.name); });

TEST(BadInputCorpus, HasAtLeastFiftyCasesInEveryCategory) {
  const auto v = corpus();
  EXPECT_GE(v.size(), 50u);
  std::map<std::string, int> per;
  for (const auto& c : v) ++per[c.category];
  for (const char* cat : {"dataset", "calibration", "config", "set", "trajectory", "run folder", "output"})
    EXPECT_GE(per[cat], 3) << cat;
}

}  // namespace
