// T_BS from sensor.yaml, and camera-frame estimates compared with body ground truth through it.
#include "rsvio/eval/extrinsic.h"

#include <gtest/gtest.h>

#include "eval_test_util.h"
#include "rsvio/core/error.h"
#include "rsvio/eval/evaluate_files.h"

using namespace rsvio;
using namespace rsvio::eval;

namespace {

// EuRoC's cam0 extrinsic (MH_01 sensor.yaml), as printed there.
const char* kSensorYaml = R"(# General sensor definitions.
sensor_type: camera
comment: VI-Sensor cam0 (MT9M034)

# Sensor extrinsics wrt. the body-frame.
T_BS:
  cols: 4
  rows: 4
  data: [0.0148655429818, -0.999880929698, 0.00414029679422, -0.0216401454975,
         0.999557249008, 0.0149672133247, 0.025715529948, -0.064676986768,
        -0.0257744366974, 0.00375618835797, 0.999660727178, 0.00981073058949,
         0.0, 0.0, 0.0, 1.0]

# Camera specific definitions.
rate_hz: 20
resolution: [752, 480]
)";

std::string eurocStateCsv(const io::Trajectory& t) {
  std::string s = "#timestamp, p_x, p_y, p_z, q_w, q_x, q_y, q_z, v_x, v_y, v_z, bw_x, bw_y, bw_z, ba_x, ba_y, ba_z\n";
  char buf[400];
  for (const auto& p : t.poses) {
    std::snprintf(buf, sizeof(buf), "%lld,%.12f,%.12f,%.12f,%.12f,%.12f,%.12f,%.12f,0,0,0,0,0,0,0,0,0\n",
                  static_cast<long long>(p.t_ns), p.p_W_X.x(), p.p_W_X.y(), p.p_W_X.z(), p.q_W_X.w(), p.q_W_X.x(),
                  p.q_W_X.y(), p.q_W_X.z());
    s += buf;
  }
  return s;
}

class ExtrinsicTest : public test::TempDirTest {};

}  // namespace

TEST_F(ExtrinsicTest, ReadsEurocTBS) {
  const Eigen::Isometry3d T = readSensorYamlTBS(write("sensor.yaml", kSensorYaml));
  EXPECT_NEAR(T.translation().x(), -0.0216401454975, 1e-12);
  EXPECT_NEAR(T.translation().y(), -0.064676986768, 1e-12);
  EXPECT_NEAR(T.linear()(0, 1), -0.999880929698, 1e-6);
  EXPECT_NEAR(T.linear()(2, 2), 0.999660727178, 1e-6);
  EXPECT_LT((T.linear().transpose() * T.linear() - Eigen::Matrix3d::Identity()).norm(), 1e-12);
}

TEST_F(ExtrinsicTest, BadYamlMessagesNameFileAndLine) {
  auto errorOf = [&](const std::string& text) -> std::string {
    try {
      readSensorYamlTBS(write("bad.yaml", text));
    } catch (const DataError& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(errorOf("rate_hz: 20\n").find("key 'T_BS' not found"), std::string::npos);
  std::string e = errorOf("T_BS:\n  data: [1, 0, 0, 0,\n 0, 1, 0, 0]\n");
  EXPECT_NE(e.find("bad.yaml:1: T_BS data: expected 16 numbers"), std::string::npos) << e;
  e = errorOf("T_BS:\n  data: [2, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]\n");
  EXPECT_NE(e.find("not a rotation"), std::string::npos) << e;
  e = errorOf("T_BS:\n  data: [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, x]\n");
  EXPECT_NE(e.find("not a number"), std::string::npos) << e;
  EXPECT_THROW(readSensorYamlTBS(path("missing.yaml")), DataError);
}

TEST_F(ExtrinsicTest, MapBodyToCameraComposesOnTheRight) {
  io::Trajectory body;
  io::StampedPose p;
  p.p_W_X = Eigen::Vector3d(1, 2, 3);
  p.q_W_X = Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()));
  body.poses.push_back(p);
  Eigen::Isometry3d T_B_C = Eigen::Isometry3d::Identity();
  T_B_C.translation() = Eigen::Vector3d(0.1, 0, 0);
  const io::Trajectory cam = mapBodyToCamera(body, T_B_C);
  EXPECT_EQ(cam.frame, io::PoseFrame::kCamera);
  // The camera sits 0.1 m along the body's x axis, which points along world y after the 90 degree yaw.
  EXPECT_LT((cam.poses[0].p_W_X - Eigen::Vector3d(1, 2.1, 3)).norm(), 1e-12);
}

TEST_F(ExtrinsicTest, CameraEstimateIsComparedThroughTBS) {
  const io::Trajectory gt_body = test::lissajous(200, 50'000'000);
  write("ds/mav0/state_groundtruth_estimate0/data.csv", eurocStateCsv(gt_body));
  const std::string yaml = write("ds/mav0/cam0/sensor.yaml", kSensorYaml);
  // A VO estimate: camera poses in its own world and scale.
  io::Trajectory cam = mapBodyToCamera(gt_body, readSensorYamlTBS(yaml));
  cam = test::transformed(cam, 0.5, Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitX())),
                          Eigen::Vector3d(1, 2, 3));
  cam.frame = io::PoseFrame::kCamera;
  io::writeTum(path("est.tum"), cam);

  FileEvalRequest req;
  req.dataset_dir = path("ds");
  req.est_path = path("est.tum");
  const FileEvalOutcome o = evaluateFiles(req);
  EXPECT_EQ(o.result.alignment.mode, AlignMode::kSim3);  // default for camera poses
  EXPECT_NEAR(o.result.alignment.scale, 2.0, 1e-6);
  EXPECT_LT(o.result.ate_m.max, 1e-6);
  EXPECT_LT(o.result.ate_rot_deg.max, 1e-5);
  EXPECT_NE(o.context.frame_mapping.find("T_BS of"), std::string::npos);

  // Without the mapping the lever arm and the rotation show: a wrong (identity) T_BS is visibly worse.
  const std::string identity = write("identity.yaml", "T_BS:\n  data: [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]\n");
  req.calib_path = identity;
  EXPECT_GT(evaluateFiles(req).result.ate_rot_deg.max, 10.0);

  // A ground-truth file without calibration cannot be compared with camera poses.
  FileEvalRequest bare;
  bare.gt_path = path("ds/mav0/state_groundtruth_estimate0/data.csv");
  bare.est_path = path("est.tum");
  try {
    evaluateFiles(bare);
    FAIL() << "no throw";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("--calib"), std::string::npos) << e.what();
  }
  bare.calib_path = yaml;
  EXPECT_LT(evaluateFiles(bare).result.ate_m.max, 1e-6);
}

TEST_F(ExtrinsicTest, DatasetWithoutGroundTruthIsADataError) {
  std::filesystem::create_directories(path("empty/mav0"));
  FileEvalRequest req;
  req.dataset_dir = path("empty");
  req.est_path = write("e.tum", "1.0 0 0 0 0 0 0 1\n");
  try {
    evaluateFiles(req);
    FAIL() << "no throw";
  } catch (const DataError& e) {
    EXPECT_NE(std::string(e.what()).find("no ground truth"), std::string::npos) << e.what();
  }
}

// FileEvalRequest's span: estimates outside [est_from_ns, est_to_ns] are left out before association
// (diagnose --against compares two runs over the frames both tracked). The estimate is exact for its
// first half and 0.5 m off after it: over the first half the ATE is zero, over the whole it is not.
TEST_F(ExtrinsicTest, EstimatesOutsideTheSpanAreLeftOut) {
  const io::Trajectory gt = test::lissajous(200, 50'000'000);
  write("ds/mav0/state_groundtruth_estimate0/data.csv", eurocStateCsv(gt));
  io::Trajectory est = gt;
  est.frame = io::PoseFrame::kBody;
  for (size_t i = 100; i < est.poses.size(); ++i) est.poses[i].p_W_X.z() += 0.5;
  io::writeTum(path("half.tum"), est);
  FileEvalRequest req;
  req.dataset_dir = path("ds");
  req.est_path = path("half.tum");
  const FileEvalOutcome whole = evaluateFiles(req);
  EXPECT_EQ(whole.estimates_in_span, 200u);
  EXPECT_GT(whole.result.ate_m.rmse, 0.1);
  req.est_from_ns = gt.poses[10].t_ns;
  req.est_to_ns = gt.poses[99].t_ns;  // inclusive
  const FileEvalOutcome first = evaluateFiles(req);
  EXPECT_EQ(first.estimates_in_span, 90u);
  EXPECT_EQ(first.result.association.pairs.size(), 90u);
  EXPECT_LT(first.result.ate_m.rmse, 1e-6);
  req.est_from_ns = gt.poses.back().t_ns + 1;  // nothing left: an error that says so, not an ATE of 0
  req.est_to_ns = req.est_from_ns + 1000;
  EXPECT_THROW(evaluateFiles(req), Error);
}
