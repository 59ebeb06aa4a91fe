// The comparison grid with fake children: a bounded pool that survives crashes, non-zero exits,
// timeouts and programs that do not exist; reading reports back; the summary and its files.
#include "rsvio/eval/compare.h"

#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "eval_test_util.h"

using namespace rsvio;
using namespace rsvio::eval;
namespace fs = std::filesystem;

namespace {

class CompareTest : public test::TempDirTest {};

std::vector<std::string> sh(const std::string& script) { return {"/bin/sh", "-c", script}; }

std::string readFile(const std::string& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace

TEST_F(CompareTest, PoolReportsEveryKindOfEnding) {
  std::vector<ChildSpec> children = {
      {sh("echo hello; echo oops >&2; exit 0"), path("ok.log")},
      {sh("echo about to fail; exit 5"), path("exit.log")},
      {sh("kill -SEGV $$"), path("segv.log")},
      {sh("exec sleep 30"), path("slow.log")},
      {{path("no_such_program")}, path("missing.log")},
  };
  PoolOptions opt;
  opt.max_workers = 2;
  opt.timeout_s = 0.5;
  const auto out = runChildProcesses(children, opt);
  ASSERT_EQ(out.size(), 5u);
  EXPECT_TRUE(out[0].ok());
  EXPECT_EQ(readFile(path("ok.log")), "hello\noops\n");  // stdout and stderr both in the log
  EXPECT_EQ(out[1].kind, ChildOutcome::Kind::kExited);
  EXPECT_EQ(out[1].code, 5);
  EXPECT_EQ(out[1].describe(), "exit code 5");
  EXPECT_EQ(out[2].kind, ChildOutcome::Kind::kSignaled);
  EXPECT_EQ(out[2].code, SIGSEGV);
  EXPECT_NE(out[2].describe().find("killed by signal 11"), std::string::npos) << out[2].describe();
  EXPECT_EQ(out[3].kind, ChildOutcome::Kind::kTimedOut);
  EXPECT_EQ(out[3].describe(), "timed out after 0.5 s (killed)");
  EXPECT_EQ(out[4].kind, ChildOutcome::Kind::kSpawnFailed);
  EXPECT_FALSE(out[4].ok());
  EXPECT_NE(out[4].describe().find("could not start"), std::string::npos);
}

TEST_F(CompareTest, PoolNeverRunsMoreThanMaxWorkers) {
  // Each child marks itself present in a shared folder and records how many are present; the pool's
  // own start/done callbacks give the same count from the parent's side.
  fs::create_directories(path("present"));
  std::vector<ChildSpec> children;
  for (int i = 0; i < 6; ++i) {
    const std::string me = path("present/" + std::to_string(i));
    children.push_back({sh("touch " + me + "; ls " + path("present") + " | wc -l >> " + path("counts") +
                           "; sleep 0.2; rm " + me),
                        path("c" + std::to_string(i) + ".log")});
  }
  PoolOptions opt;
  opt.max_workers = 2;
  int running = 0, most = 0;
  std::vector<size_t> finished;
  const auto out = runChildProcesses(
      children, opt, [&](size_t) { most = std::max(most, ++running); },
      [&](size_t i, const ChildOutcome&) {
        --running;
        finished.push_back(i);
      });
  for (const auto& o : out) EXPECT_TRUE(o.ok()) << o.describe();
  EXPECT_EQ(finished.size(), 6u);
  EXPECT_LE(most, 2);
  std::istringstream counts(readFile(path("counts")));
  int n = 0, seen = 0;
  while (counts >> n) {
    EXPECT_GE(n, 1);
    EXPECT_LE(n, 2);
    ++seen;
  }
  EXPECT_EQ(seen, 6);
}

TEST_F(CompareTest, PlanNamesFoldersUniquelyAndOrdersJobs) {
  const auto jobs = planCompareJobs({"cfg/gs_vo.json", "other/gs_vo.json"}, {"data/seq01/", "data/seq 02"}, 2, "out");
  ASSERT_EQ(jobs.size(), 8u);
  EXPECT_EQ(jobs[0].config_name, "gs_vo");
  EXPECT_EQ(jobs[4].config_name, "gs_vo_2");
  EXPECT_EQ(jobs[0].dataset_name, "seq01");
  EXPECT_EQ(jobs[2].dataset_name, "seq_02");
  EXPECT_EQ(jobs[1].run, 1);
  EXPECT_EQ(jobs[1].out_dir, "out/runs/gs_vo/seq01/1");
  const auto argv = rsvioRunArgv("/bin/rsvio", {"--plugin-path=/p"}, jobs[1]);
  const std::vector<std::string> expect{"/bin/rsvio", "--plugin-path=/p", "run", "--config", "cfg/gs_vo.json", "--data",
                                        "data/seq01/", "--out", "out/runs/gs_vo/seq01/1", "--seed", "1"};
  EXPECT_EQ(argv, expect);
}

TEST_F(CompareTest, GridCountsFailuresReadsReportsAndEvaluatesTrajectories) {
  // Dataset with ground truth (EuRoC mocap) for runs whose report has no eval.
  const io::Trajectory gt = test::lissajous(100, 50'000'000);
  std::string mocap = "#t,x,y,z,qw,qx,qy,qz\n";
  for (const auto& p : gt.poses) {
    mocap += std::to_string(p.t_ns) + "," + std::to_string(p.p_W_X.x()) + "," + std::to_string(p.p_W_X.y()) + "," +
             std::to_string(p.p_W_X.z()) + ",1,0,0,0\n";
  }
  write("seq01/mav0/mocap0/data.csv", mocap);
  io::Trajectory est = gt;
  est.frame = io::PoseFrame::kBody;
  for (auto& p : est.poses) p.q_W_X = Eigen::Quaterniond::Identity();
  io::writeTum(path("kf.tum"), est);
  write("good.json", "{}");
  write("bad.json", "{}");
  write("other.json", "{}");

  const auto jobs = planCompareJobs({path("good.json"), path("bad.json"), path("other.json")}, {path("seq01")}, 3,
                                    path("out"));
  // The fake child: "good" writes a report with eval (ATE 0.1 * (k + 1)); "bad" crashes on seed 0, exits 3
  // with a message on seed 1, reports failed on seed 2; "other" reports ok without eval and leaves a
  // keyframes.tum to evaluate.
  const RunArgvBuilder builder = [&](const CompareJob& j) {
    std::string script;
    const std::string rep = j.out_dir + "/report.json";
    if (j.config_name == "good") {
      script = "echo '{\"status\":\"ok\",\"fps\":" + std::to_string(10 + j.run) +
               ",\"realtime_factor\":0.5,\"eval\":{\"ate_rmse_m\":" + std::to_string(0.1 * (j.run + 1)) +
               ",\"align\":\"se3\"}}' > " + rep;
    } else if (j.config_name == "bad") {
      script = j.run == 0   ? "kill -SEGV $$"
               : j.run == 1 ? "echo 'rsvio run: not available yet' >&2; exit 3"
                            : "echo '{\"status\":\"failed\",\"error\":\"diverged at frame 12\"}' > " + rep;
    } else {
      script = "cp " + path("kf.tum") + " " + j.out_dir + "/keyframes.tum; echo '{\"status\":\"ok\",\"fps\":20}' > " + rep;
    }
    return sh(script);
  };
  std::ostringstream progress;
  CompareOptions opt;
  opt.jobs = 2;
  const CompareResult r = runCompare(jobs, builder, opt, &progress);

  ASSERT_EQ(r.runs.size(), 9u);
  EXPECT_EQ(r.failed(), 3u);
  // Every run is recorded with its own folder and log.
  for (const auto& x : r.runs) EXPECT_TRUE(fs::exists(x.log_path)) << x.log_path;
  EXPECT_TRUE(r.runs[0].ok);
  EXPECT_NEAR(*r.runs[1].ate_rmse_m, 0.2, 1e-12);
  EXPECT_EQ(r.runs[1].align, "se3");
  EXPECT_NE(r.runs[3].error.find("killed by signal 11"), std::string::npos) << r.runs[3].error;
  EXPECT_EQ(r.runs[4].error, "exit code 3: rsvio run: not available yet");
  EXPECT_EQ(r.runs[5].error, "diverged at frame 12");
  ASSERT_TRUE(r.runs[6].ok);
  ASSERT_TRUE(r.runs[6].ate_rmse_m) << r.runs[6].eval_note;
  EXPECT_LT(*r.runs[6].ate_rmse_m, 1e-5);  // the estimate is the ground truth (written to 9 decimals)
  EXPECT_EQ(r.runs[6].align, "se3");
  EXPECT_NE(r.runs[6].eval_note.find("keyframes.tum"), std::string::npos);

  ASSERT_EQ(r.groups.size(), 3u);
  const GroupSummary& good = r.groups[0];
  EXPECT_EQ(good.config_name, "good");
  EXPECT_EQ(good.runs, 3u);
  EXPECT_EQ(good.failed, 0u);
  EXPECT_NEAR(*good.ate_median_m, 0.2, 1e-12);
  EXPECT_NEAR(*good.ate_mean_m, 0.2, 1e-12);
  EXPECT_NEAR(*good.fps_median, 11.0, 1e-12);
  const GroupSummary& bad = r.groups[1];
  EXPECT_EQ(bad.failed, 3u);
  EXPECT_FALSE(bad.ate_median_m);

  // Progress: one line per run, counted.
  const std::string prog = progress.str();
  EXPECT_NE(prog.find("/9] good on seq01 run 1: ok ATE 0.2 m 11.0 fps"), std::string::npos) << prog;
  EXPECT_NE(prog.find("bad on seq01 run 1: FAILED (exit code 3"), std::string::npos) << prog;
  EXPECT_NE(prog.find("[9/9]"), std::string::npos) << prog;

  writeCompareOutputs(path("out"), r);
  const auto j = nlohmann::json::parse(readFile(path("out/compare.json")));
  EXPECT_EQ(j["failed"], 3);
  EXPECT_EQ(j["runs"].size(), 9u);
  EXPECT_EQ(j["runs"][5]["status"], "failed");
  EXPECT_EQ(j["runs"][5]["error"], "diverged at frame 12");
  EXPECT_EQ(j["summary"][1]["status"], "all_failed");
  EXPECT_EQ(j["summary"][0]["ate_median_m"], 0.2);
  const std::string csv = readFile(path("out/compare.csv"));
  EXPECT_NE(csv.find("summary,good,seq01,,ok,3,0,0.2,0.2,11,11,,,,,"), std::string::npos) << csv;
  EXPECT_NE(csv.find("run,bad,seq01,1,failed,,,,,,,,,,,exit code 3: rsvio run: not available yet"), std::string::npos)
      << csv;
  const std::string table = formatCompareTable(r);
  EXPECT_NE(table.find("6 of 9 runs ok, 3 failed"), std::string::npos) << table;
}

TEST_F(CompareTest, StaleReportOfAnEarlierComparisonIsNotReused) {
  write("c.json", "{}");
  fs::create_directories(path("d"));
  const auto jobs = planCompareJobs({path("c.json")}, {path("d")}, 1, path("out"));
  write("out/runs/c/d/0/report.json", "{\"status\":\"ok\",\"fps\":1}");
  const auto r = runCompare(jobs, [](const CompareJob&) { return sh("exit 0"); }, CompareOptions{}, nullptr);
  EXPECT_FALSE(r.runs[0].ok);
  EXPECT_EQ(r.runs[0].error, "exit code 0 but no report.json was written");
}
