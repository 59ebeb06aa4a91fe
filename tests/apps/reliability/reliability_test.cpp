// Reliability of `rsvio run` and `rsvio compare` on a real (small) simulated sequence (configs/sim/
// tiny_gs.json, 3 s, 320x256), through the CLI binary ($RSVIO_BIN):
// - SIGINT / SIGTERM during a run: it stops at the next frame, writes every output so far with
//   report.json status "interrupted" and exits 130; every file parses.
// - SIGKILL at 8 seeded moments (4 in the sanitizer build): every file left parses, a report.json
//   included (outputs are written to a temporary and renamed); a new run into the
//   same folder leaves none of the killed run's files.
// - A failed re-run into the folder of an earlier good run: no file of the good run survives.
// - Repeatability (conventions.md, Determinism): the same config, data, seed and threads twice give the
//   same bytes in every output; report.json is compared without its wall-time fields (fps,
//   realtime_factor, stage_ms).
// - `rsvio compare`: SIGINT stops the children (none left running), writes the table of the finished
//   runs and exits 130; --resume keeps the finished runs (config hash, data, seed) and runs the rest.
// Nothing here measures time: moments are chosen from a progress line or from a seeded generator.
#include <gtest/gtest.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "rsvio/io/diagnostics_log.h"
#include "rsvio/io/ply.h"
#include "rsvio/io/report.h"
#include "rsvio/io/states.h"
#include "rsvio/io/trajectory.h"

namespace fs = std::filesystem;

namespace {

const std::string kSrc = RSVIO_SOURCE_DIR;

std::string rsvioBin() {
  const char* b = std::getenv("RSVIO_BIN");
  return b ? b : std::string(RSVIO_BINARY_DIR) + "/bin/rsvio";
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// A child rsvio with stdout and stderr in `log`.
pid_t spawn(const std::vector<std::string>& args, const fs::path& log) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    ::dup2(fd, 1);
    ::dup2(fd, 2);
    std::vector<char*> argv;
    const std::string bin = rsvioBin();
    argv.push_back(const_cast<char*>(bin.c_str()));
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execv(bin.c_str(), argv.data());
    ::_exit(127);
  }
  return pid;
}

// Exit code, or 128 + signal.
int waitExit(pid_t pid) {
  int st = 0;
  while (::waitpid(pid, &st, 0) < 0 && errno == EINTR) {
  }
  return WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
}

// Polls `log` until it holds `text` (true) or the child has ended (false). A guard of 10 minutes keeps
// a hung child from hanging the suite; it is not a measurement.
bool waitForText(pid_t pid, const fs::path& log, const std::string& text) {
  for (int i = 0; i < 60000; ++i) {
    if (slurp(log).find(text) != std::string::npos) return true;
    int st = 0;
    if (::waitpid(pid, &st, WNOHANG) == pid) {
      return false;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return false;
}

int runCli(const std::vector<std::string>& args, const fs::path& log) { return waitExit(spawn(args, log)); }

const char* kFiles[] = {"trajectory.tum", "keyframes.tum", "states.csv", "points.ply", "config.json",
                        "diagnostics.bin", "report.json"};

// Every contract file in `dir` that exists parses; returns what did not.
std::string unreadableFiles(const fs::path& dir) {
  std::string bad;
  auto check = [&](const char* name, const std::function<void(const std::string&)>& read) {
    const fs::path p = dir / name;
    if (!fs::exists(p)) return;
    try {
      read(p.string());
    } catch (const std::exception& e) {
      bad += std::string(name) + ": " + e.what() + "\n";
    }
  };
  check("trajectory.tum", [](const std::string& p) { (void)rsvio::io::readTum(p); });
  check("keyframes.tum", [](const std::string& p) { (void)rsvio::io::readTum(p); });
  check("states.csv", [](const std::string& p) { (void)rsvio::readStates(p); });
  check("points.ply", [](const std::string& p) { (void)rsvio::io::readPly(p); });
  check("diagnostics.bin", [](const std::string& p) { (void)rsvio::DiagnosticsLog::read(p); });
  check("config.json", [](const std::string& p) { const auto j = nlohmann::json::parse(slurp(p)); (void)j; });
  check("report.json", [](const std::string& p) { (void)rsvio::Report::read(p); });
  return bad;
}

class Reliability : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    root_ = fs::temp_directory_path() / ("rsvio_reliability_" + std::to_string(::getpid()));
    fs::remove_all(root_);
    fs::create_directories(root_);
    const int code = runCli({"-q", "simulate", "--config", kSrc + "/configs/sim/tiny_gs.json", "--out", data()},
                            root_ / "simulate.log");
    ASSERT_EQ(code, 0) << slurp(root_ / "simulate.log");
  }
  static void TearDownTestSuite() {
    std::error_code ec;
    fs::remove_all(root_, ec);
  }
  static std::string data() { return (root_ / "data").string(); }
  static std::vector<std::string> runArgs(const fs::path& out, bool verbose = false) {
    std::vector<std::string> a;
    if (verbose) a.push_back("-v");
    for (const std::string& s : {std::string("run"), std::string("--config"), kSrc + "/configs/gs_vo.json",
                                 std::string("--data"), data(), std::string("--out"), out.string(), std::string("--set"),
                                 std::string("output.render=false")})
      a.push_back(s);
    return a;
  }
  fs::path dir(const std::string& name) const { return root_ / name; }
  static fs::path root_;
};
fs::path Reliability::root_;

void expectInterrupted(int sig, const fs::path& out, const fs::path& log) {
  const std::string ctx = slurp(log);
  const auto rep = nlohmann::json::parse(slurp(out / "report.json"));
  EXPECT_EQ(rep["status"], "interrupted") << ctx;
  EXPECT_NE(rep["error"].get<std::string>().find(sig == SIGINT ? "SIGINT" : "SIGTERM"), std::string::npos) << rep.dump();
  EXPECT_GE(rep["frames"].get<int>(), 5) << rep.dump();
  EXPECT_LT(rep["frames"].get<int>(), 60) << rep.dump();
  for (const char* f : kFiles) EXPECT_TRUE(fs::exists(out / f)) << f << "\n" << ctx;
  EXPECT_EQ(unreadableFiles(out), "");
  // Every frame processed so far is in the trajectory (tracked ones), none after the stop.
  EXPECT_LE(rsvio::io::readTum((out / "trajectory.tum").string()).poses.size(), rep["frames"].get<size_t>());
  EXPECT_NE(ctx.find("interrupted by"), std::string::npos) << ctx;
}

}  // namespace

TEST_F(Reliability, SigintAndSigtermStopAtTheNextFrameAndKeepTheOutputs) {
  for (int sig : {SIGINT, SIGTERM}) {
    const fs::path out = dir(sig == SIGINT ? "int" : "term"), log = dir(sig == SIGINT ? "int.log" : "term.log");
    const pid_t pid = spawn(runArgs(out, /*verbose=*/true), log);
    ASSERT_TRUE(waitForText(pid, log, "[6/")) << slurp(log);
    ::kill(pid, sig);
    EXPECT_EQ(waitExit(pid), 130) << slurp(log);
    expectInterrupted(sig, out, log);
  }
}

TEST_F(Reliability, KillNineAtAnyMomentNeverLeavesAReportBesideTruncatedFiles) {
  // A complete run first: how long one takes bounds the kill moments (no assertion on time).
  const fs::path ref = dir("ref");
  const auto t0 = std::chrono::steady_clock::now();
  ASSERT_EQ(runCli(runArgs(ref), dir("ref.log")), 0) << slurp(dir("ref.log"));
  const double full_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  const int frames = nlohmann::json::parse(slurp(ref / "report.json"))["frames"].get<int>();
  const std::string last_frame = "[" + std::to_string(frames) + "/" + std::to_string(frames) + "]";
  std::mt19937 rng(16);
  const fs::path out = dir("killed");
  int with_report = 0;
#ifdef RSVIO_SANITIZE
  const int kills = 4;  // sanitizer build: each run is several times slower
#else
  const int kills = 8;
#endif
  for (int k = 0; k < kills; ++k) {
    const pid_t pid = spawn(runArgs(out), dir("killed.log"));
    if (k % 2 == 0) {
      // Files are written after the last frame: half the kills land 0-500 ms after its progress line.
      waitForText(pid, dir("killed.log"), last_frame);
      std::this_thread::sleep_for(std::chrono::milliseconds(std::uniform_int_distribution<int>(0, 500)(rng)));
    } else {
      const double frac = std::uniform_real_distribution<double>(0.0, 1.0)(rng);
      std::this_thread::sleep_for(std::chrono::microseconds(static_cast<long>(frac * full_ms * 1000)));
    }
    ::kill(pid, SIGKILL);
    waitExit(pid);
    // Every file written is complete, report or not (each one is renamed into place whole).
    EXPECT_EQ(unreadableFiles(out), "") << "kill " << k;
    if (fs::exists(out / "report.json")) {
      ++with_report;
      const auto rep = rsvio::Report::read((out / "report.json").string());
      if (rep.ok())
        for (const char* f : kFiles) EXPECT_TRUE(fs::exists(out / f)) << f << " missing beside an ok report";
    }
  }
  // The next run into the same folder leaves nothing of the killed ones (temporaries included).
  ASSERT_EQ(runCli(runArgs(out), dir("killed.log")), 0) << slurp(dir("killed.log"));
  for (const auto& e : fs::directory_iterator(out))
    EXPECT_EQ(e.path().filename().string().find(".tmp-"), std::string::npos) << e.path();
  EXPECT_EQ(unreadableFiles(out), "");
  std::printf("[reliability] %d kills -9 (run of %.0f ms), %d left a report.json\n", kills, full_ms, with_report);
}

TEST_F(Reliability, AFailedRerunLeavesNoFileOfTheEarlierGoodRun) {
  const fs::path out = dir("stale");
  ASSERT_EQ(runCli(runArgs(out), dir("stale.log")), 0) << slurp(dir("stale.log"));
  fs::create_directories(out / "figures");
  std::ofstream(out / "figures" / "old.png") << "x";
  std::ofstream(out / "index.html") << "old";
  std::ofstream(out / "report.json.tmp-1") << "partial";
  std::ofstream(out / "notes.txt") << "the user's own file";
  // Same data with the frames from the 10th on unreadable: the run fails part way (exit 1).
  const fs::path bad = dir("bad_data");
  fs::copy(data(), bad, fs::copy_options::recursive);
  std::vector<fs::path> imgs;
  for (const auto& e : fs::directory_iterator(bad / "mav0" / "cam0" / "data")) imgs.push_back(e.path());
  std::sort(imgs.begin(), imgs.end());
  for (size_t i = 10; i < imgs.size(); ++i) std::ofstream(imgs[i]) << "not a png";
  auto args = runArgs(out);
  args[4] = bad.string();
  EXPECT_EQ(runCli(args, dir("stale2.log")), 1) << slurp(dir("stale2.log"));
  const auto rep = nlohmann::json::parse(slurp(out / "report.json"));
  EXPECT_EQ(rep["status"], "failed");
  EXPECT_FALSE(fs::exists(out / "figures"));
  EXPECT_FALSE(fs::exists(out / "index.html"));
  EXPECT_FALSE(fs::exists(out / "report.json.tmp-1"));
  EXPECT_TRUE(fs::exists(out / "notes.txt"));  // not rsvio's: left alone
  EXPECT_EQ(unreadableFiles(out), "");
  EXPECT_LT(rep["frames"].get<int>(), 11);
}

TEST_F(Reliability, SameConfigDataSeedAndThreadsGiveTheSameBytes) {
  // Both runs write into the same folder (report.json names it), the first one's files are moved away.
  const fs::path a = dir("rep_first"), b = dir("rep");
  for (int k = 0; k < 2; ++k) {
    auto args = runArgs(b);
    for (const std::string& s : {std::string("--seed"), std::string("3"), std::string("--set"), std::string("threads=2")})
      args.push_back(s);
    ASSERT_EQ(runCli(args, dir("rep.log")), 0) << slurp(dir("rep.log"));
    if (k == 0) fs::rename(b, a);
  }
  for (const char* f : kFiles) {
    if (std::string(f) == "report.json") continue;
    ASSERT_TRUE(fs::exists(a / f)) << f;
    EXPECT_TRUE(slurp(a / f) == slurp(b / f)) << f << " differs between two identical runs";
  }
  // report.json: every field but the wall-time ones.
  auto strip = [](nlohmann::json j) {
    for (const char* k : {"fps", "realtime_factor", "stage_ms"}) j.erase(k);
    return j;
  };
  const auto ra = nlohmann::json::parse(slurp(a / "report.json")), rb = nlohmann::json::parse(slurp(b / "report.json"));
  EXPECT_EQ(strip(ra).dump(), strip(rb).dump());
  EXPECT_EQ(ra["status"], "ok");
}

TEST_F(Reliability, CompareStopsItsChildrenOnSigintAndResumes) {
  const fs::path out = dir("grid"), log = dir("grid.log");
  std::vector<std::string> args{"compare", "--configs", kSrc + "/configs/gs_vo.json", "--data", data(),
                                "--runs", "3", "--jobs", "1", "--no-figures", "--out", out.string(),
                                "--set", "output.render=false"};
  const pid_t pid = spawn(args, log);
  ASSERT_TRUE(waitForText(pid, log, "[1/3]")) << slurp(log);
  // Run 1 is starting now (its folder holds job.json, written just before its child starts).
  for (int i = 0; i < 60000 && !fs::exists(out / "runs" / "gs_vo" / "data" / "1" / "log.txt"); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  ::kill(pid, SIGINT);
  EXPECT_EQ(waitExit(pid), 130) << slurp(log);
  const std::string text = slurp(log);
  EXPECT_NE(text.find("--resume"), std::string::npos) << text;
  auto j = nlohmann::json::parse(slurp(out / "compare.json"));
  ASSERT_EQ(j["runs"].size(), 3u);
  EXPECT_EQ(j["runs"][0]["status"], "ok") << j.dump(2);
  EXPECT_EQ(j["runs"][1]["status"], "interrupted") << j.dump(2);
  EXPECT_EQ(j["runs"][2]["status"], "not run") << j.dump(2);
  EXPECT_TRUE(j["interrupted"].get<bool>());
  ASSERT_EQ(j["summary"].size(), 1u);
  EXPECT_EQ(j["summary"][0]["runs"], 1);  // the table holds the finished run
  // The interrupted child stopped (compare waits for it): its report, when it got as far, says so.
  const fs::path rep1 = out / "runs" / "gs_vo" / "data" / "1" / "report.json";
  if (fs::exists(rep1)) EXPECT_EQ(nlohmann::json::parse(slurp(rep1))["status"], "interrupted");
  EXPECT_FALSE(fs::exists(out / "runs" / "gs_vo" / "data" / "2" / "report.json"));
  const std::string report0 = slurp(out / "runs" / "gs_vo" / "data" / "0" / "report.json");

  args.push_back("--resume");
  EXPECT_EQ(runCli(args, log), 0) << slurp(log);
  j = nlohmann::json::parse(slurp(out / "compare.json"));
  ASSERT_EQ(j["runs"].size(), 3u);
  for (const auto& r : j["runs"]) EXPECT_EQ(r["status"], "ok") << j.dump(2);
  EXPECT_TRUE(j["runs"][0]["kept"].get<bool>());
  EXPECT_FALSE(j["runs"][1]["kept"].get<bool>());
  EXPECT_EQ(slurp(out / "runs" / "gs_vo" / "data" / "0" / "report.json"), report0);  // not run again
  EXPECT_EQ(j["summary"][0]["runs"], 3);

  // A changed --set changes the config hash: nothing is kept.
  args.back() = "--resume";
  args.insert(args.end() - 1, {"--set", "frontend.points=301"});
  std::vector<std::string> changed = args;
  EXPECT_EQ(runCli(changed, log), 0) << slurp(log);
  j = nlohmann::json::parse(slurp(out / "compare.json"));
  for (const auto& r : j["runs"]) EXPECT_FALSE(r["kept"].get<bool>()) << j.dump(2);
}
