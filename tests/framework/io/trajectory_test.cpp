// TUM / EuRoC trajectory files: round trip, exact time stamps, column orders, and the messages a bad
// file gets (path:line, the field, what was wrong).
#include "rsvio/io/trajectory.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "rsvio/core/error.h"

namespace fs = std::filesystem;
using namespace rsvio;
using namespace rsvio::io;

namespace {

class TrajectoryFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("rsvio_traj_test_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string write(const std::string& name, const std::string& text) {
    const std::string p = (dir_ / name).string();
    fs::create_directories(fs::path(p).parent_path());
    std::ofstream(p) << text;
    return p;
  }
  // The DataError message of reading `text` with `reader`, or "" when it did not throw.
  template <typename F>
  std::string errorOf(const std::string& text, F reader, const std::string& name = "bad.txt") {
    const std::string p = write(name, text);
    try {
      reader(p);
    } catch (const DataError& e) {
      return e.what();
    }
    return "";
  }
  fs::path dir_;
};

}  // namespace

TEST(ParseSecondsToNs, DecimalStringsAreExact) {
  EXPECT_EQ(parseSecondsToNs("1311868164.363181"), 1311868164363181000LL);
  EXPECT_EQ(parseSecondsToNs("1305031098.6659"), 1305031098665900000LL);
  EXPECT_EQ(parseSecondsToNs("1403715524.912143104"), 1403715524912143104LL);
  EXPECT_EQ(parseSecondsToNs("0.0000000015"), 2);  // 10th decimal rounds
  EXPECT_EQ(parseSecondsToNs("-1.5"), -1500000000LL);
  EXPECT_EQ(parseSecondsToNs("7"), 7000000000LL);
  EXPECT_EQ(parseSecondsToNs(".25"), 250000000LL);
}

TEST(ParseSecondsToNs, ExponentNotationIsExactToo) {
  // evo writes stamps like this; through double they would be off by up to ~0.1 us.
  EXPECT_EQ(parseSecondsToNs("1.403715529112143517e+09"), 1403715529112143517LL);
  EXPECT_EQ(parseSecondsToNs("-2.5E-3"), -2500000LL);
  EXPECT_EQ(parseSecondsToNs("15e2"), 1500000000000LL);
  EXPECT_EQ(parseSecondsToNs("1.5e-10"), 0);
  EXPECT_FALSE(parseSecondsToNs("1e"));
  EXPECT_FALSE(parseSecondsToNs("1e5x"));
  EXPECT_FALSE(parseSecondsToNs("1e999"));
}

TEST(ParseSecondsToNs, RejectsGarbage) {
  for (const char* bad : {"", "abc", "1.2.3", "nan", "inf", "1e999", "12x", "-", ".", "e5", "12345678901.0"}) {
    EXPECT_FALSE(parseSecondsToNs(bad)) << bad;
  }
}

TEST_F(TrajectoryFileTest, RoundTripKeepsFrameStampsAndQuaternionOrder) {
  Trajectory t;
  t.frame = PoseFrame::kCamera;
  StampedPose a;
  a.t_ns = 1403715524912143104LL;
  a.p_W_X = Eigen::Vector3d(1.25, -2.5, 0.125);
  a.q_W_X = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()));
  StampedPose b = a;
  b.t_ns += 50'000'001;
  t.poses = {a, b};
  const std::string p = (dir_ / "t.tum").string();
  writeTum(p, t);

  std::ifstream in(p);
  std::string line1, line2;
  std::getline(in, line1);
  std::getline(in, line2);
  EXPECT_EQ(line1, "# frame: camera");
  // 9 decimals of seconds, then x y z, then qx qy qz qw (TUM order, w last).
  char expect[200];
  std::snprintf(expect, sizeof(expect), "1403715524.912143104 1.250000000 -2.500000000 0.125000000 %.9f %.9f %.9f %.9f",
                a.q_W_X.x(), a.q_W_X.y(), a.q_W_X.z(), a.q_W_X.w());
  EXPECT_EQ(line2, expect);

  const Trajectory r = readTum(p);
  EXPECT_EQ(r.frame, PoseFrame::kCamera);
  ASSERT_EQ(r.size(), 2u);
  EXPECT_EQ(r.poses[0].t_ns, a.t_ns);
  EXPECT_EQ(r.poses[1].t_ns, b.t_ns);
  EXPECT_LT((r.poses[0].p_W_X - a.p_W_X).norm(), 1e-9);
  EXPECT_LT(r.poses[0].q_W_X.angularDistance(a.q_W_X), 1e-8);
}

TEST_F(TrajectoryFileTest, BodyHeaderAndNoHeader) {
  EXPECT_EQ(readTum(write("b.tum", "# frame: body\n1.0 0 0 0 0 0 0 1\n")).frame, PoseFrame::kBody);
  const Trajectory u = readTum(write("u.tum", "# some comment\n1.0 0 0 0 0 0 0 1\n\n2.0 1 0 0 0 0 0 1\n"));
  EXPECT_EQ(u.frame, PoseFrame::kUnknown);
  EXPECT_EQ(u.size(), 2u);
}

TEST_F(TrajectoryFileTest, EqualStampsAreKeptDecreasingOnesAreErrors) {
  EXPECT_EQ(readTum(write("eq.tum", "1.0 0 0 0 0 0 0 1\n1.0 0 0 0 0 0 0 1\n")).size(), 2u);
  const std::string e = errorOf("1.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0 0 1\n1.5 0 0 0 0 0 0 1\n", readTum);
  EXPECT_NE(e.find("bad.txt:3:"), std::string::npos) << e;
  EXPECT_NE(e.find("earlier than the previous"), std::string::npos) << e;
}

TEST_F(TrajectoryFileTest, BadTumLinesNameLineAndField) {
  std::string e = errorOf("# frame: body\n1.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0 1\n", readTum);
  EXPECT_NE(e.find("bad.txt:3: expected 8 columns"), std::string::npos) << e;
  EXPECT_NE(e.find("found 7"), std::string::npos) << e;

  e = errorOf("1.0 0 nan 0 0 0 0 1\n", readTum);
  EXPECT_NE(e.find("bad.txt:1: field 'ty'"), std::string::npos) << e;
  EXPECT_NE(e.find("finite"), std::string::npos) << e;

  e = errorOf("1.0 0 0 0 0 0 0 x1\n", readTum);
  EXPECT_NE(e.find("field 'qw' is not a number"), std::string::npos) << e;

  e = errorOf("1,0,0,0,0,0,0,1\n", readTum);
  EXPECT_NE(e.find("space separated"), std::string::npos) << e;

  e = errorOf("1.0 0 0 0 0 0 0 0\n", readTum);
  EXPECT_NE(e.find("quaternion (qx qy qz qw) has norm 0"), std::string::npos) << e;

  e = errorOf("# frame: world\n1.0 0 0 0 0 0 0 1\n", readTum);
  EXPECT_NE(e.find("bad.txt:1: header 'frame' is 'world'"), std::string::npos) << e;

  e = errorOf("abc 0 0 0 0 0 0 1\n", readTum);
  EXPECT_NE(e.find("field 't'"), std::string::npos) << e;
}

TEST_F(TrajectoryFileTest, MissingFileIsDataError) {
  EXPECT_THROW(readTum((dir_ / "nope.tum").string()), DataError);
  EXPECT_THROW(readGroundTruth((dir_ / "nope.csv").string()), DataError);
}

TEST_F(TrajectoryFileTest, EurocStateGroundTruthColumnOrder) {
  const std::string p = write("gt.csv",
                              "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], "
                              "q_RS_z [], v x, v y, v z, bw x, bw y, bw z, ba x, ba y, ba z\r\n"
                              "1403715524907143168,0.5,2.0,0.9,0.0,1.0,0.0,0.0,0.1,0.2,0.3,0.01,0.02,0.03,0.4,0.5,0.6\r\n"
                              "1403715524912143104, 0.6, 2.0, 0.9, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0\r\n");
  const auto rows = readEurocStateGroundTruth(p);
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].t_ns, 1403715524907143168LL);
  EXPECT_EQ(rows[0].p_W_B, Eigen::Vector3d(0.5, 2.0, 0.9));
  // w first in the file: (w, x, y, z) = (0, 1, 0, 0) is a half turn about x.
  EXPECT_DOUBLE_EQ(rows[0].q_W_B.w(), 0.0);
  EXPECT_DOUBLE_EQ(rows[0].q_W_B.x(), 1.0);
  EXPECT_EQ(rows[0].v_W_B, Eigen::Vector3d(0.1, 0.2, 0.3));
  EXPECT_EQ(rows[0].bg, Eigen::Vector3d(0.01, 0.02, 0.03));
  EXPECT_EQ(rows[0].ba, Eigen::Vector3d(0.4, 0.5, 0.6));

  const Trajectory t = readGroundTruth(p);
  EXPECT_EQ(t.frame, PoseFrame::kBody);
  ASSERT_EQ(t.size(), 2u);
  EXPECT_DOUBLE_EQ(t.poses[1].p_W_X.x(), 0.6);
}

TEST_F(TrajectoryFileTest, EurocMocapAndTumGroundTruth) {
  const std::string m = write("mocap.csv", "#timestamp [ns],x,y,z,qw,qx,qy,qz\n100,1,2,3,1,0,0,0\n200,1,2,3,0,0,0,1\n");
  const Trajectory tm = readGroundTruth(m);
  EXPECT_EQ(tm.frame, PoseFrame::kBody);
  ASSERT_EQ(tm.size(), 2u);
  EXPECT_EQ(tm.poses[1].t_ns, 200);
  EXPECT_DOUBLE_EQ(tm.poses[1].q_W_X.z(), 1.0);

  const std::string tum = write("fr.txt",
                                "# ground truth trajectory\n# file: 'x.bag'\n# timestamp tx ty tz qx qy qz qw\n"
                                "1311868163.8697 -0.1357 -1.4217 1.4764 0.6453 -0.5498 0.3363 -0.4101\n");
  const Trajectory tt = readGroundTruth(tum);
  EXPECT_EQ(tt.frame, PoseFrame::kUnknown);
  ASSERT_EQ(tt.size(), 1u);
  EXPECT_EQ(tt.poses[0].t_ns, 1311868163869700000LL);
  EXPECT_NEAR(tt.poses[0].q_W_X.w(), -0.4101, 1e-3);  // normalised, w last in TUM
}

TEST_F(TrajectoryFileTest, BadEurocRowsNameLineAndField) {
  std::string e = errorOf("#h\n100,1,2,3,1,0,0,0,0,0,0,0,0,0,0,0,0\n200,1,2,3,1,0,0,0,0,0,0,0,0,0,0,0\n",
                          readEurocStateGroundTruth, "s.csv");
  EXPECT_NE(e.find("s.csv:3: expected 17 comma-separated columns"), std::string::npos) << e;
  e = errorOf("100,1,2,3,1,0,0,0\n50,1,2,3,1,0,0,0\n", readEurocMocap, "m.csv");
  EXPECT_NE(e.find("m.csv:2: timestamp"), std::string::npos) << e;
  e = errorOf("100,1,inf,3,1,0,0,0\n", readEurocMocap, "m2.csv");
  EXPECT_NE(e.find("m2.csv:1: field 'p_y'"), std::string::npos) << e;
  e = errorOf("1.5e9,1,2,3,1,0,0,0\n", readEurocMocap, "m3.csv");
  EXPECT_NE(e.find("field 'timestamp' is not an integer nanosecond"), std::string::npos) << e;
  e = errorOf("100,1,2,3,1\n", readGroundTruth, "g.csv");
  EXPECT_NE(e.find("g.csv:1: comma-separated ground truth needs 17 columns"), std::string::npos) << e;
}

TEST_F(TrajectoryFileTest, DatasetGroundTruthPrefersStateEstimate) {
  const fs::path ds = dir_ / "ds";
  EXPECT_FALSE(findDatasetGroundTruth(ds.string()));
  write("ds/mav0/mocap0/data.csv", "100,1,2,3,1,0,0,0\n");
  EXPECT_EQ(findDatasetGroundTruth(ds.string()), (ds / "mav0/mocap0/data.csv").string());
  write("ds/mav0/state_groundtruth_estimate0/data.csv", "100,1,2,3,1,0,0,0,0,0,0,0,0,0,0,0,0\n");
  EXPECT_EQ(findDatasetGroundTruth(ds.string()), (ds / "mav0/state_groundtruth_estimate0/data.csv").string());
}
