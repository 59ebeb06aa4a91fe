// A newcomer's path through the CLI (issue 18): what the terminal says when a user makes the usual
// mistakes, and the exit codes of the README's table (0 ok, 1 run failed, 2 bad input or usage,
// 3 not available, 130 interrupted).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

namespace fs = std::filesystem;

namespace {

struct Result {
  int code = -1;
  std::string out, err;
};

std::string slurp(const fs::path& p) {
  std::ifstream f(p);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

fs::path scratch() {
  static const fs::path dir = fs::temp_directory_path() / ("rsvio_newcomer_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir;
}

// Runs `rsvio <args>` with stdout and stderr kept apart.
Result rsvio(const std::string& args) {
  const char* bin = std::getenv("RSVIO_BIN");
  const std::string exe = bin ? std::string(bin) : std::string(RSVIO_BINARY_DIR) + "/bin/rsvio";
  const fs::path o = scratch() / "stdout.txt", e = scratch() / "stderr.txt";
  const std::string cmd = exe + " " + args + " >" + o.string() + " 2>" + e.string();
  const int status = std::system(cmd.c_str());
  Result r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : 128;
  r.out = slurp(o);
  r.err = slurp(e);
  return r;
}

size_t lines(const std::string& s) {
  size_t n = 0;
  for (char c : s) n += c == '\n';
  return n;
}

size_t count(const std::string& s, const std::string& what) {
  size_t n = 0;
  for (size_t k = s.find(what); k != std::string::npos; k = s.find(what, k + 1)) ++n;
  return n;
}

const std::string kSrc = RSVIO_SOURCE_DIR;

// A tiny simulated dataset shared by the tests of this file (simulated once).
const fs::path& tinyData() {
  static const fs::path data = [] {
    const fs::path d = scratch() / "tiny_gs";
    const Result r = rsvio("-q simulate --config " + kSrc + "/configs/sim/tiny_gs.json --out " + d.string());
    EXPECT_EQ(r.code, 0) << r.err;
    return d;
  }();
  return data;
}

class Newcomer : public ::testing::Test {
 protected:
  static void TearDownTestSuite() { fs::remove_all(scratch()); }
};

// ---- 1. Config: a null on a key that does not exist, a typo in a --set key ----------------------------

TEST_F(Newcomer, SetNullOnAMissingKeyIsAnErrorWithDidYouMeanInSimulate) {
  const fs::path out = scratch() / "sim_typo";
  const Result r = rsvio("simulate --config " + kSrc + "/configs/sim/tiny_rs.json --out " + out.string() +
                         " --set effects.rolling_shuter=null");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("--set effects.rolling_shuter=null: effects.rolling_shuter: unknown key"), std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("did you mean \"effects.rolling_shutter\"?"), std::string::npos) << r.err;
  EXPECT_EQ(lines(r.err), 1u) << r.err;
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(Newcomer, SetNullOnAMissingKeyIsAnErrorWithDidYouMeanInRun) {
  const fs::path out = scratch() / "run_typo";
  const Result r = rsvio("run --config " + kSrc + "/configs/gs_vo.json --data " + scratch().string() + " --out " +
                         out.string() + " --set photometric.afine=null");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("photometric.afine: unknown key"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("did you mean \"photometric.affine\"?"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
  // A null on a key that exists still removes it (the config is then valid: the run gets as far as the data).
  const Result ok = rsvio("run --config " + kSrc + "/configs/gs_vo.json --data " + (scratch() / "nope").string() +
                          " --out " + out.string() + " --set photometric.affine=null");
  EXPECT_EQ(ok.code, 2);
  EXPECT_EQ(ok.err.find("photometric"), std::string::npos) << ok.err;
  EXPECT_NE(ok.err.find("nope"), std::string::npos) << ok.err;
}

TEST_F(Newcomer, TypoInASetKeyBlamesTheSetArgumentNotTheFile) {
  const Result r = rsvio("run --config " + kSrc + "/configs/gs_vo.json --data " + scratch().string() + " --out " +
                         (scratch() / "x").string() + " --set backend.activ_points=100");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("--set backend.activ_points=100: backend.activ_points: unknown key; did you mean "
                       "\"active_points\"?"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(r.err.find("gs_vo.json"), std::string::npos) << "the file is not to blame: " << r.err;
  // A problem of the file itself still names the file.
  std::ofstream(scratch() / "bad.json") << R"({"extends": ")" + kSrc + R"(/configs/gs_vo.json", "backend": {"activ_points": 1}})";
  const Result f = rsvio("run --config " + (scratch() / "bad.json").string() + " --data " + scratch().string() +
                         " --out " + (scratch() / "x").string());
  EXPECT_EQ(f.code, 2);
  EXPECT_NE(f.err.find("bad.json: backend.activ_points: unknown key"), std::string::npos) << f.err;
}

// ---- 2. Warnings on stderr, what a run did not use ------------------------------------------------------

TEST_F(Newcomer, RunOneLevelTooDeepSaysNoGroundTruthAndPrintsWarningsOnce) {
  const fs::path out = scratch() / "deep";
  const Result r = rsvio("run --config " + kSrc + "/configs/gs_vo.json --data " + (tinyData() / "mav0").string() +
                         " --out " + out.string() + " --set output.render=false");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("run ok"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("not used:"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("ground truth (none found in"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("one level too deep"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("IMU (ignored"), std::string::npos) << r.out;
  // Every warning of report.json is on stderr, once.
  const auto rep = nlohmann::json::parse(slurp(out / "report.json"));
  ASSERT_TRUE(rep.contains("warnings")) << rep.dump();
  ASSERT_FALSE(rep["warnings"].empty());
  for (const auto& w : rep["warnings"]) EXPECT_EQ(count(r.err, w.get<std::string>()), 1u) << w << "\n" << r.err;
}

TEST_F(Newcomer, TruncatedImuLineIsAWarningOnStderr) {
  const fs::path data = scratch() / "truncated";
  fs::remove_all(data);
  fs::copy(tinyData(), data, fs::copy_options::recursive);
  const fs::path imu = data / "mav0/imu0/data.csv";
  std::string text = slurp(imu);
  ASSERT_GT(text.size(), 40u);
  text.resize(text.size() - 20);  // cut the last line in the middle
  std::ofstream(imu, std::ios::trunc) << text;
  const Result r = rsvio("run --config " + kSrc + "/configs/gs_vo.json --data " + data.string() + " --out " +
                         (scratch() / "trunc_run").string() + " --set output.render=false");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(count(r.err, "last line is truncated"), 1u) << r.err;
  EXPECT_NE(r.err.find("rsvio run: warning: "), std::string::npos) << r.err;
  // With ground truth found, the summary does not claim it is missing.
  EXPECT_EQ(r.out.find("ground truth (none found"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("ATE"), std::string::npos) << r.out;
}

// rsvio eval: an RPE step longer than the sequence has no pair; its row says "-", not an error of 0.
TEST_F(Newcomer, EvalRpeRowWithoutPairsPrintsDashes) {
  const fs::path run = scratch() / "eval_run";
  const Result r = rsvio("-q run --config " + kSrc + "/configs/gs_vo.json --data " + tinyData().string() + " --out " +
                         run.string() + " --set output.render=false");
  ASSERT_EQ(r.code, 0) << r.err;
  const Result e = rsvio("eval --data " + tinyData().string() + " --est " + (run / "keyframes.tum").string() +
                         " --rpe-windows-s 0.5,100");
  ASSERT_EQ(e.code, 0) << e.err;
  std::istringstream in(e.out);
  std::string line;
  bool saw_empty = false, saw_full = false;
  while (std::getline(in, line)) {
    if (line.rfind("  100 s ", 0) == 0) {
      saw_empty = true;
      EXPECT_EQ(line.find("0.000000"), std::string::npos) << line;
      EXPECT_EQ(std::count(line.begin(), line.end(), '-'), 5) << "pairs 0, every statistic '-': " << line;
    }
    if (line.rfind("  0.5 s ", 0) == 0) saw_full = std::count(line.begin(), line.end(), '-') == 1;  // drift only
  }
  EXPECT_TRUE(saw_empty) << e.out;
  EXPECT_TRUE(saw_full) << e.out;
}

// ---- 3. A rolling-shutter run without a line delay says how to give it --------------------------------

TEST_F(Newcomer, RollingShutterWithoutLineDelaySaysHowToGiveIt) {
  const Result r = rsvio("run --config " + kSrc + "/configs/rs_vo.json --data " + tinyData().string() + " --out " +
                         (scratch() / "rs").string() + " --set output.render=false");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("--set shutter.params.line_delay_us="), std::string::npos) << r.err;
  // Whether shutter.rolling offers estimate_line_delay: its parameter table, as rsvio plugins lists it.
  bool can_estimate = false;
  const Result pl = rsvio("plugins --json");
  const nlohmann::json listing = nlohmann::json::parse(pl.out);  // named: a loop over a temporary's member dangles
  for (const auto& p : listing["plugins"])
    if (p["name"] == "shutter.rolling")
      for (const auto& q : p["params"]) can_estimate |= q["key"] == "estimate_line_delay";
  EXPECT_EQ(r.err.find("shutter.params.estimate_line_delay=true") != std::string::npos, can_estimate) << r.err;
}

// ---- 4. Exit codes and one-line usage errors -------------------------------------------------------------

TEST_F(Newcomer, UsageErrorsAreOneLineAndExitTwo) {
  for (const std::string args :
       {std::string(""), std::string("frobnicate"), std::string("run --frobnicate"),
        "run --config " + (scratch() / "missing.json").string() + " --data x --out y",
        "--plugin-path " + (scratch() / "no_such_plugins").string() + " plugins",
        "run --config " + kSrc + "/configs/gs_vo.json --data " + scratch().string() + " --out y --seed -1",
        "simulate --config " + kSrc + "/configs/sim/tiny_gs.json --out y --seed -1", std::string("eval --est")}) {
    const Result r = rsvio(args);
    EXPECT_EQ(r.code, 2) << "rsvio " << args << "\n" << r.err;
    EXPECT_EQ(lines(r.err), 1u) << "rsvio " << args << "\n" << r.err;
    EXPECT_EQ(r.err.rfind("rsvio", 0), 0u) << r.err;
  }
  EXPECT_NE(rsvio("").err.find("a subcommand is required: demo plugins simulate run eval compare"), std::string::npos);
  EXPECT_NE(rsvio("--plugin-path /no/such/dir plugins").err.find("/no/such/dir"), std::string::npos);
  EXPECT_EQ(rsvio("--help").code, 0);
  EXPECT_EQ(rsvio("run --help").code, 0);
}

TEST_F(Newcomer, EmptyOutAndMissingDataAreNamedAndLeaveNoFolder) {
  const Result e = rsvio("run --config " + kSrc + "/configs/gs_vo.json --data " + tinyData().string() + " --out \"\"");
  EXPECT_EQ(e.code, 2);
  EXPECT_NE(e.err.find("--out: empty output folder name"), std::string::npos) << e.err;
  EXPECT_EQ(e.err.find(": : "), std::string::npos) << e.err;
  const fs::path out = scratch() / "never";
  const Result m = rsvio("run --config " + kSrc + "/configs/gs_vo.json --data " + (scratch() / "nonexistent").string() +
                         " --out " + out.string());
  EXPECT_EQ(m.code, 2);
  EXPECT_NE(m.err.find("nonexistent"), std::string::npos) << m.err;
  EXPECT_FALSE(fs::exists(out)) << "a run that never started left its output folder";
}

// ---- 5. rsvio plugins ---------------------------------------------------------------------------------

// Start columns of the first `n` fields of a parameter row (fields are separated by 2+ spaces).
std::vector<size_t> columnStarts(const std::string& line, size_t n) {
  std::vector<size_t> starts;
  size_t i = line.find_first_not_of(' ');
  while (i != std::string::npos && starts.size() < n) {
    starts.push_back(i);
    const size_t gap = line.find("  ", i);
    if (gap == std::string::npos) break;
    i = line.find_first_not_of(' ', gap);
  }
  return starts;
}

TEST_F(Newcomer, PluginsTableIsAlignedAndListsFrameworkKeys) {
  const Result r = rsvio("plugins");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.out.find("\n  (none)\n"), std::string::npos) << "a kind without plugins says 'none yet' on its header line";
  // Parameter rows (6-space indent) of one block share their column starts: key, type, unit, default.
  std::istringstream in(r.out);
  std::string line;
  std::vector<size_t> block;
  size_t rows = 0;
  while (std::getline(in, line)) {
    if (line.rfind("      ", 0) != 0 || line[6] == ' ') {
      block.clear();
      continue;
    }
    const auto starts = columnStarts(line, 4);
    if (starts.size() < 4) continue;
    ++rows;
    if (block.empty()) block = starts;
    else EXPECT_EQ(starts, block) << line;
  }
  EXPECT_GT(rows, 20u);
  for (const char* key : {"frontend.points", "backend.active_points", "backend.max_keyframes", "output.render",
                          "[run config keys]", "[simulation config keys]"})
    EXPECT_NE(r.out.find(key), std::string::npos) << key;
  const Result j = rsvio("plugins --json");
  ASSERT_EQ(j.code, 0);
  const auto js = nlohmann::json::parse(j.out);
  EXPECT_FALSE(js["run_config"]["frontend"]["params"].empty());
  EXPECT_FALSE(js["run_config"]["backend"]["params"].empty());
}

// A plugin folder holding libraries that cannot be loaded (tests' bad plugins): listed, exit 2, one line.
TEST_F(Newcomer, RejectedPluginLibrariesAreBadInput) {
  const Result r = rsvio(std::string("--plugin-path ") + RSVIO_TEST_PLUGIN_DIR + " plugins");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.out.find("rejected: "), std::string::npos) << r.out;
  EXPECT_NE(r.err.find("rejected"), std::string::npos) << r.err;
  EXPECT_EQ(lines(r.err), 1u) << r.err;
}

}  // namespace
