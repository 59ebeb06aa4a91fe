// The rsvio binary as users call it: exit codes and one-line messages on stderr.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

namespace fs = std::filesystem;

namespace {

struct Output {
  int code = -1;
  std::string out;  // stdout and stderr together
};

Output runRsvio(const std::string& args) {
  const char* bin = std::getenv("RSVIO_BIN");  // ctest sets it; else the binary of this build
  const std::string cmd = (bin ? std::string(bin) : std::string(RSVIO_BINARY_DIR) + "/bin/rsvio") + " " + args + " 2>&1";
  Output o;
  FILE* p = ::popen(cmd.c_str(), "r");
  if (!p) return o;
  std::array<char, 4096> buf{};
  size_t n;
  while ((n = std::fread(buf.data(), 1, buf.size(), p)) > 0) o.out.append(buf.data(), n);
  const int status = ::pclose(p);
  o.code = WIFEXITED(status) ? WEXITSTATUS(status) : 128;
  return o;
}

}  // namespace

TEST(Cli, PluginsJsonListsKindsAndParameters) {
  const Output o = runRsvio("plugins --json");
  ASSERT_EQ(o.code, 0) << o.out;
  const auto j = nlohmann::json::parse(o.out);
  ASSERT_TRUE(j["plugins"].is_array());
  bool found_camera = false;
  for (const auto& p : j["plugins"]) {
    EXPECT_TRUE(p.contains("kind") && p.contains("version") && p.contains("description") && p.contains("params"));
    if (p["name"] == "camera.pinhole") found_camera = true;
    for (const auto& q : p["params"]) {
      EXPECT_TRUE(q.contains("type") && q.contains("unit") && q.contains("default")) << p["name"];
    }
  }
  EXPECT_TRUE(found_camera);
  EXPECT_TRUE(j["rejected"].empty()) << j["rejected"].dump();
}

TEST(Cli, PluginsTableNamesEveryKind) {
  const Output o = runRsvio("plugins");
  ASSERT_EQ(o.code, 0) << o.out;
  for (const char* k : {"[camera]", "[shutter]", "[motion]", "[photometric]", "[solver]", "[source]", "[effect]",
                        "[probe]"})
    EXPECT_NE(o.out.find(k), std::string::npos) << k;
}

TEST(Cli, UnknownSubcommandFails) {
  const Output o = runRsvio("frobnicate");
  EXPECT_NE(o.code, 0);
}

TEST(Cli, MissingConfigFileIsNamed) {
  const Output o = runRsvio("run --config /nonexistent/cfg.json --data /tmp --out /tmp/x");
  EXPECT_NE(o.code, 0);
  EXPECT_NE(o.out.find("/nonexistent/cfg.json"), std::string::npos) << o.out;
}

TEST(Cli, BadConfigKeyGetsPathAndSuggestion) {
  const fs::path dir = fs::temp_directory_path() / ("rsvio_cli_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::ofstream(dir / "cfg.json") << R"({"camera": {"plugin": "camera.pinhol"}, "outptu": {}})";
  const Output o = runRsvio("run --config " + (dir / "cfg.json").string() + " --data " + dir.string() + " --out " +
                            (dir / "out").string());
  fs::remove_all(dir);
  EXPECT_EQ(o.code, 2) << o.out;
  EXPECT_NE(o.out.find("camera.plugin: unknown plugin 'camera.pinhol'; did you mean 'camera.pinhole'?"),
            std::string::npos)
      << o.out;
  EXPECT_NE(o.out.find("outptu: unknown key; did you mean \"output\"?"), std::string::npos) << o.out;
}

TEST(Cli, BadSetIsReported) {
  const fs::path dir = fs::temp_directory_path() / ("rsvio_cli_set_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::ofstream(dir / "cfg.json") << "{}";
  const Output o = runRsvio("run --config " + (dir / "cfg.json").string() + " --data " + dir.string() + " --out " +
                            (dir / "out").string() + " --set threads=0");
  fs::remove_all(dir);
  EXPECT_EQ(o.code, 2) << o.out;
  EXPECT_NE(o.out.find("threads: expected an integer in [1, 64], found 0"), std::string::npos) << o.out;
}

// `rsvio run` end to end on a tiny simulated sequence: exit 0 and every file of the user contract, with
// report.json's required fields (user-contract.md, "Files a run writes").
TEST(Cli, RunWritesTheContractFiles) {
  const fs::path dir = fs::temp_directory_path() / ("rsvio_cli_run_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const std::string src = RSVIO_SOURCE_DIR;
  const Output sim = runRsvio("simulate --config " + src + "/configs/sim/tiny_gs.json --out " + (dir / "data").string());
  ASSERT_EQ(sim.code, 0) << sim.out;
  const Output o = runRsvio("run --config " + src + "/configs/gs_vo.json --data " + (dir / "data").string() +
                            " --out " + (dir / "run").string() + " --set output.render=false");
  ASSERT_EQ(o.code, 0) << o.out;
  EXPECT_NE(o.out.find("run ok"), std::string::npos) << o.out;
  for (const char* f : {"trajectory.tum", "keyframes.tum", "points.ply", "states.csv", "config.json", "report.json",
                        "diagnostics.bin"})
    EXPECT_TRUE(fs::exists(dir / "run" / f)) << f;
  std::ifstream rf(dir / "run" / "report.json");
  const auto rep = nlohmann::json::parse(rf);
  EXPECT_EQ(rep["status"], "ok");
  for (const char* k : {"frames", "keyframes", "fps", "realtime_factor", "stage_ms", "eval"})
    EXPECT_TRUE(rep.contains(k)) << k;
  EXPECT_GT(rep["keyframes"].get<int>(), 3);
  EXPECT_EQ(rep["eval"]["align"], "sim3");
  EXPECT_LT(rep["eval"]["ate_rmse_m"].get<double>(), 0.05);
  std::ifstream tf(dir / "run" / "trajectory.tum");
  std::string first;
  std::getline(tf, first);
  EXPECT_EQ(first, "# frame: camera");
  // A missing dataset folder: exit 2 and the folder named.
  const Output bad = runRsvio("run --config " + src + "/configs/gs_vo.json --data " + (dir / "nope").string() +
                              " --out " + (dir / "run2").string());
  EXPECT_EQ(bad.code, 2) << bad.out;
  EXPECT_NE(bad.out.find((dir / "nope").string()), std::string::npos) << bad.out;
  fs::remove_all(dir);
}
