// `rsvio compare` end to end. While `rsvio run` does not exist every run fails with its message kept;
// with a stand-in runner (hidden --runner) the success path, the table and the exit codes are checked.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <nlohmann/json.hpp>

#include "cli_test_util.h"

using rsvio::test::quote;
using rsvio::test::slurp;
namespace fs = std::filesystem;

namespace {
class CompareCli : public rsvio::test::CliTest {};
}  // namespace

TEST_F(CompareCli, EveryFailedChildIsCountedAndTheTableIsStillWritten) {
  // A deliberately failing config on a tiny dataset. Today `rsvio run` itself fails ("not available
  // yet"); once it lands, the config is invalid, so the runs still fail. Either way: counted, kept.
  const std::string cfg = write("broken.json", "{\"estimator\": {\"plugin\": \"no_such.plugin\"}}");
  write("tiny/mav0/mocap0/data.csv", "100,0,0,0,1,0,0,0\n");
  const auto r = run("compare --configs " + quote(cfg) + " --data " + quote(path("tiny")) + " --runs 2 --out " +
                     quote(path("out")));
  EXPECT_EQ(r.exit_code, 1) << r.out << r.err;
  EXPECT_NE(r.out.find("[2/2] broken on tiny run"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("0 of 2 runs ok, 2 failed"), std::string::npos) << r.out;
  const auto j = nlohmann::json::parse(slurp(path("out/compare.json")));
  ASSERT_EQ(j["runs"].size(), 2u);
  for (const auto& x : j["runs"]) {
    EXPECT_EQ(x["status"], "failed");
    EXPECT_FALSE(x["error"].get<std::string>().empty());
    EXPECT_TRUE(fs::exists(x["log"].get<std::string>()));
  }
  EXPECT_EQ(j["summary"][0]["failed"], 2);
  // The child's own words reach the record: its report's error when it wrote one, else the last line
  // of its log.
  const std::string err0 = j["runs"][0]["error"].get<std::string>();
  const std::string report0 = path("out/runs/broken/tiny/0/report.json");
  if (fs::exists(report0)) {
    const auto rep = nlohmann::json::parse(slurp(report0));
    EXPECT_NE(err0.find(rep.value("error", std::string("?"))), std::string::npos) << err0;
  } else {
    const std::string log0 = slurp(path("out/runs/broken/tiny/0/log.txt"));
    ASSERT_FALSE(log0.empty());
    std::string last = log0.substr(0, log0.find_last_not_of('\n') + 1);
    last = last.substr(last.find_last_of('\n') + 1);
    EXPECT_NE(err0.find(last), std::string::npos) << err0 << " vs " << last;
  }
  EXPECT_TRUE(fs::exists(path("out/compare.csv")));
}

TEST_F(CompareCli, StandInRunnerSucceedsAndFails) {
  // The runner gets rsvio run's arguments: run --config C --data D --out O --seed k.
  const std::string runner = write("runner.sh",
                                   "#!/bin/sh\n"
                                   "while [ $# -gt 0 ]; do case $1 in --out) out=$2;; --seed) seed=$2;; --config) cfg=$2;; esac; shift; done\n"
                                   "case $cfg in *crash*) kill -ABRT $$;; esac\n"
                                   "echo \"{\\\"status\\\":\\\"ok\\\",\\\"fps\\\":25,\\\"eval\\\":{\\\"ate_rmse_m\\\":0.0$seed,\\\"align\\\":\\\"se3\\\"}}\" > $out/report.json\n");
  ::chmod(runner.c_str(), 0755);
  const std::string good = write("good.json", "{}"), crash = write("crash.json", "{}");
  fs::create_directories(path("seqA"));
  fs::create_directories(path("seqB"));
  auto r = run("compare --runner " + quote(runner) + " --configs " + quote(good) + " --data " + quote(path("seqA")) + " " +
               quote(path("seqB")) + " --runs 3 --jobs 2 --no-figures --out " + quote(path("out")));
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("ok ATE 0.01 m 25.0 fps"), std::string::npos) << r.out;
  auto j = nlohmann::json::parse(slurp(path("out/compare.json")));
  ASSERT_EQ(j["summary"].size(), 2u);
  EXPECT_NEAR(j["summary"][0]["ate_median_m"].get<double>(), 0.01, 1e-12);  // seeds 0, 1, 2
  EXPECT_NEAR(j["summary"][1]["ate_mean_m"].get<double>(), 0.01, 1e-12);

  r = run("compare --runner " + quote(runner) + " --configs " + quote(good) + " " + quote(crash) + " --data " +
          quote(path("seqA")) + " --no-figures --out " + quote(path("out2")));
  EXPECT_EQ(r.exit_code, 1) << r.out << r.err;
  EXPECT_NE(r.out.find("crash on seqA run 0: FAILED (killed by signal 6"), std::string::npos) << r.out;
}

TEST_F(CompareCli, UsageErrorsExitTwo) {
  fs::create_directories(path("d"));
  const std::string cfg = write("c.json", "{}");
  EXPECT_EQ(run("compare --configs " + quote(path("missing.json")) + " --data " + quote(path("d")) + " --out " +
                quote(path("o"))).exit_code, 2);
  EXPECT_EQ(run("compare --configs " + quote(cfg) + " --data " + quote(path("nope")) + " --out " + quote(path("o")))
                .exit_code, 2);
  EXPECT_EQ(run("compare --configs " + quote(cfg) + " --data " + quote(path("d")) + " --runs 0 --out " + quote(path("o")))
                .exit_code, 2);
}
