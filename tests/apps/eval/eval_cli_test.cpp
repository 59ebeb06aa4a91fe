// `rsvio eval` end to end: table, JSON, --out files, exit codes and messages.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "cli_test_util.h"

using rsvio::test::quote;

namespace {

class EvalCli : public rsvio::test::CliTest {
 protected:
  std::string ref(const std::string& f) const { return quote(std::string(RSVIO_SHARED_DIR) + "/data/eval-reference/" + f); }
};

}  // namespace

TEST_F(EvalCli, JsonOnReferencePair) {
  const auto r = run("eval --gt " + ref("fr2_desk_groundtruth.txt") + " --est " + ref("fr2_desk_ORB.txt") +
                     " --align se3 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_NEAR(j["ate_rmse_m"].get<double>(), 0.008119, 1e-5);
  EXPECT_EQ(j["align"], "se3");
  EXPECT_EQ(j["association"]["pairs"], 2174);
  EXPECT_DOUBLE_EQ(j["association"]["max_dt_s"].get<double>(), 0.01);
  EXPECT_NE(j["association"]["rule"].get<std::string>().find("nearest ground-truth stamp"), std::string::npos);
  EXPECT_GE(j["rpe"].size(), 8u);
  EXPECT_DOUBLE_EQ(j["alignment"]["scale"].get<double>(), 1.0);
}

TEST_F(EvalCli, TableAndOutFiles) {
  const auto r = run("eval --gt " + ref("V102_groundtruth.csv") + " --est " + ref("V102.txt") + " --align sim3 --out " +
                     quote(path("o")));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("798 pairs of 807 estimates"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("Sim(3), scale 0.97"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("0.083841"), std::string::npos) << r.out;
  const auto j = nlohmann::json::parse(rsvio::test::slurp(path("o/eval.json")));
  EXPECT_NEAR(j["ate_rmse_m"].get<double>(), 0.083841, 1e-5);
  const std::string csv = rsvio::test::slurp(path("o/error_over_time.csv"));
  EXPECT_EQ(csv.rfind("t_s,dt_s,trans_err_m,rot_err_deg,", 0), 0u);
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 799);
  EXPECT_NE(csv.find("\n1403715529.112143517,"), std::string::npos);  // exact stamp as read
}

TEST_F(EvalCli, MaxDtChangesTheAssociation) {
  const auto r = run("eval --gt " + ref("fr2_desk_groundtruth.txt") + " --est " + ref("fr2_desk_ORB.txt") +
                     " --max-dt 0.001 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_LT(j["association"]["pairs"].get<int>(), 2174);
  EXPECT_LE(j["association"]["largest_abs_dt_s"].get<double>(), 0.001);
}

TEST_F(EvalCli, BadFileGivesLineAndNonZeroExit) {
  const std::string bad = write("bad.tum", "# frame: body\n1.0 0 0 0 0 0 0 1\n2.0 0 0 nan 0 0 0 1\n");
  const auto r = run("eval --gt " + ref("fr2_desk_groundtruth.txt") + " --est " + quote(bad));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("bad.tum:3: field 'tz'"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;  // one line
}

TEST_F(EvalCli, UsageErrors) {
  EXPECT_EQ(run("eval --est x.tum").exit_code, 2);
  const auto r = run("eval --gt a --est b --align affine");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--align = 'affine'"), std::string::npos) << r.err;
  EXPECT_EQ(run("eval --data " + quote(path("nothing")) + " --est x.tum").exit_code, 2);
}
