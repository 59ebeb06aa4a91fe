// renderRun / renderCompare / `rsvio render`: every figure is written, index.html's links resolve to
// existing files, failed runs render (with their error), a missing display is reported, not thrown.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <regex>
#include <set>
#include <sstream>

#include "rsvio/io/diagnostics_log.h"
#include "rsvio/viz/render_run.h"
#include "run_fixture.h"

namespace rsvio::viz {
namespace {
namespace fs = std::filesystem;

std::string slurp(const fs::path& p) {
  std::ifstream f(p);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

// Every href/src of the page that is a relative link; URL escapes of the writer undone.
std::vector<std::string> relativeLinks(const std::string& html) {
  std::vector<std::string> out;
  const std::regex re(R"re((?:href|src)="([^"]+)")re");
  for (auto it = std::sregex_iterator(html.begin(), html.end(), re); it != std::sregex_iterator(); ++it) {
    std::string l = (*it)[1];
    if (l.rfind("http", 0) == 0 || l.rfind("#", 0) == 0) continue;
    for (const auto& [from, to] : std::vector<std::pair<std::string, std::string>>{{"%20", " "}, {"%23", "#"}, {"%3F", "?"},
                                                                                   {"%25", "%"}, {"&amp;", "&"}}) {
      for (size_t k; (k = l.find(from)) != std::string::npos;) l.replace(k, from.size(), to);
    }
    out.push_back(l);
  }
  return out;
}

void expectLinksResolve(const fs::path& index) {
  ASSERT_TRUE(fs::exists(index)) << index;
  const auto links = relativeLinks(slurp(index));
  EXPECT_FALSE(links.empty());
  for (const auto& l : links) {
    EXPECT_FALSE(fs::path(l).is_absolute()) << l;
    EXPECT_TRUE(fs::exists(index.parent_path() / l)) << "broken link " << l << " in " << index;
  }
}

class RenderRunTest : public ::testing::Test {
 protected:
  void SetUp() override { ::unsetenv("DISPLAY"); }
  static RenderOptions small() {
    RenderOptions o;
    o.figure = {320, 240};
    o.scene.width = 320;
    o.scene.height = 240;
    return o;
  }
};

TEST_F(RenderRunTest, RunWithGroundTruthGetsEveryFigureAndAWorkingIndex) {
  test::TempDir tmp("render_ok");
  test::RunSpec spec;
  spec.est = [](int i) { return Eigen::Vector3d(2 * std::cos(0.03 * i), 2 * std::sin(0.03 * i), 0.01 * i); };
  spec.gt = [](int i) { return Eigen::Vector3d(2 * std::cos(0.03 * i), 2 * std::sin(0.03 * i) + 0.002 * i, 0.01 * i); };
  spec.align = "se3";
  const auto run = test::makeRun(tmp.path, spec);
  DiagnosticsLog log;
  log.width = 64;
  log.height = 48;
  for (int i = 0; i < 500; ++i) {
    ObservationRow r;
    r.t_ns = test::frameTime(i % 100);
    r.u = static_cast<float>(i % 64);
    r.v = static_cast<float>(i % 48);
    r.row = r.v - 23.5f;
    r.residual = static_cast<float>(i % 7) - 3.f;
    r.weight = 1.f;
    log.observations.push_back(r);
  }
  log.write((run / "diagnostics.bin").string());

  const RenderStatus st = renderRunFolder(run.string(), small());
  EXPECT_TRUE(st.ok) << st.message;
  std::set<std::string> names;
  for (const auto& f : st.figures) {
    names.insert(fs::path(f).filename().string());
    const cv::Mat img = cv::imread(f);
    ASSERT_FALSE(img.empty()) << f;
    EXPECT_EQ(img.cols, 320) << f;
  }
  for (const char* n : {"trajectory_top.png", "trajectory_side.png", "trajectory_perspective.png", "trajectory_plan.png",
                        "error_over_time.png", "states.png", "residual_row_time.png", "residual_image.png"}) {
    EXPECT_TRUE(names.count(n)) << n;
    EXPECT_TRUE(fs::exists(run / "figures" / n)) << n;
  }
  EXPECT_EQ(st.index_html, (run / "index.html").string());
  expectLinksResolve(run / "index.html");
  const std::string html = slurp(run / "index.html");
  EXPECT_NE(html.find("trajectory_top.png"), std::string::npos);
  EXPECT_NE(html.find("tracking"), std::string::npos) << "stage times table";
}

TEST_F(RenderRunTest, FailedRunRendersAndItsPageShowsTheError) {
  test::TempDir tmp("render_failed");
  const auto run = test::makeFailedRun(tmp.path, "numerical instability at frame 12");
  const RenderStatus st = renderRunFolder(run.string(), small());
  EXPECT_TRUE(st.ok) << st.message;
  EXPECT_TRUE(fs::exists(run / "figures/trajectory_top.png"));
  EXPECT_TRUE(fs::exists(run / "figures/error_over_time.png"));
  const std::string html = slurp(run / "index.html");
  EXPECT_NE(html.find("numerical instability at frame 12"), std::string::npos);
  EXPECT_NE(html.find("badge failed"), std::string::npos);
  expectLinksResolve(run / "index.html");
}

TEST_F(RenderRunTest, NoDisplayPossibleIsReportedAnd2DFiguresStillWritten) {
  test::TempDir tmp("render_nodisplay");
  const auto run = test::makeRun(tmp.path, test::RunSpec{});
  RenderOptions o = small();
  o.display.xvfb = "Xvfb-that-does-not-exist";
  const RenderStatus st = renderRunFolder(run.string(), o);
  EXPECT_FALSE(st.ok);
  EXPECT_NE(st.message.find("xvfb"), std::string::npos) << st.message;
  EXPECT_TRUE(fs::exists(run / "figures/trajectory_plan.png"));
  EXPECT_FALSE(fs::exists(run / "figures/trajectory_top.png"));
  EXPECT_NE(slurp(run / "index.html").find("install the xvfb package"), std::string::npos);
  expectLinksResolve(run / "index.html");
}

TEST_F(RenderRunTest, MissingRunFolderIsAStatusNotAnException) {
  const RenderStatus st = renderRunFolder("/nonexistent/rsvio/run", small());
  EXPECT_FALSE(st.ok);
  EXPECT_NE(st.message.find("/nonexistent/rsvio/run"), std::string::npos);
}

TEST_F(RenderRunTest, CompareIndexLinksRunsAndFigures) {
  test::TempDir tmp("compare");
  const auto run_ok = test::makeRun(tmp.path / "a", test::RunSpec{});
  ASSERT_TRUE(renderRunFolder(run_ok.string(), [] {
                RenderOptions o = small();
                o.scenes = false;
                return o;
              }()).ok);
  const auto run_failed = test::makeFailedRun(tmp.path / "b", "diverged");
  std::vector<CompareRun> runs = {{"gs_vio", "seq 1", 0, false, 0.03, run_ok.string(), ""},
                                  {"rs_vio", "seq 1", 0, true, kNaN, run_failed.string(), "diverged"}};
  CompareRenderOptions o;
  o.out_dir = (tmp.path / "cmp").string();
  o.figure = {320, 240};
  const RenderStatus st = renderCompare(runs, o);
  EXPECT_TRUE(st.ok) << st.message;
  EXPECT_TRUE(fs::exists(tmp.path / "cmp/figures/compare_grid.png"));
  EXPECT_TRUE(fs::exists(tmp.path / "cmp/figures/ate_per_config.png"));
  expectLinksResolve(tmp.path / "cmp/index.html");
  const std::string html = slurp(tmp.path / "cmp/index.html");
  EXPECT_NE(html.find("../a/run/index.html"), std::string::npos) << "links the run's own page";
  EXPECT_NE(html.find("diverged"), std::string::npos);
}

TEST_F(RenderRunTest, RenderCommand) {
  const char* bin = std::getenv("RSVIO_BIN");
  if (!bin) GTEST_SKIP() << "RSVIO_BIN not set (run through ctest)";
  test::TempDir tmp("cli");
  const auto run = test::makeRun(tmp.path, test::RunSpec{});
  const std::string out = (tmp.path / "out").string();
  const std::string cmd = std::string(bin) + " render --run " + run.string() + " --out " + out + " --width 320 --height 240 > " +
                          (tmp.path / "log.txt").string() + " 2>&1";
  EXPECT_EQ(std::system(cmd.c_str()), 0) << slurp(tmp.path / "log.txt");
  EXPECT_TRUE(fs::exists(fs::path(out) / "trajectory_top.png"));
  // --out gets the page too; the run folder is not touched (its own page would lose its figures).
  expectLinksResolve(fs::path(out) / "index.html");
  EXPECT_FALSE(fs::exists(run / "index.html"));
  EXPECT_FALSE(fs::exists(run / "figures"));
  const std::string bad = std::string(bin) + " render --run " + (tmp.path / "nope").string() + " > " +
                          (tmp.path / "log2.txt").string() + " 2>&1";
  EXPECT_NE(std::system(bad.c_str()), 0);
  const std::string msg = slurp(tmp.path / "log2.txt");
  EXPECT_NE(msg.find("nope"), std::string::npos) << msg;
}

}  // namespace
}  // namespace rsvio::viz

namespace rsvio::viz {
namespace {

// A folder with only config.json (a run that never started, or the wrong folder): nothing to draw is
// not a success; the command says so on one line, exits 2 and writes nothing.
TEST_F(RenderRunTest, RenderCommandOnAFolderWithNothingToDrawIsAnError) {
  const char* bin = std::getenv("RSVIO_BIN");
  if (!bin) GTEST_SKIP() << "RSVIO_BIN not set (run through ctest)";
  test::TempDir tmp("cli_empty");
  const fs::path run = tmp.path / "run";
  fs::create_directories(run);
  std::ofstream(run / "config.json") << "{}";
  const std::string cmd = std::string(bin) + " render --run " + run.string() + " > " + (tmp.path / "log.txt").string() +
                          " 2>&1";
  const int status = std::system(cmd.c_str());
  EXPECT_EQ(WEXITSTATUS(status), 2) << slurp(tmp.path / "log.txt");
  const std::string msg = slurp(tmp.path / "log.txt");
  EXPECT_NE(msg.find("nothing to draw"), std::string::npos) << msg;
  EXPECT_EQ(std::count(msg.begin(), msg.end(), '\n'), 1) << msg;
  EXPECT_FALSE(fs::exists(run / "figures"));
  EXPECT_FALSE(fs::exists(run / "index.html"));
}

}  // namespace
}  // namespace rsvio::viz
