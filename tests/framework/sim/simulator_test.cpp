// The simulator end to end: seeds and shutter pairs, each image effect as its parameter says, and
// path-named errors for bad configs.
#include <gtest/gtest.h>

#include <cmath>

#include "rsvio/interfaces/camera.h"
#include "rsvio/sim/lens.h"
#include "sim_test_util.h"

namespace rsvio::sim {
namespace {

using test::effect;
using test::withEffects;

const nlohmann::json kNoEffects = nlohmann::json::object();

double maxAbsDiff(const cv::Mat& a, const cv::Mat& b) { return cv::norm(a, b, cv::NORM_INF); }

TEST(Simulator, TwoSeedsGiveDifferentData) {
  Simulator a(test::tinyConfig("tiny_gs", {"seed=1"}), test::host());
  Simulator b(test::tinyConfig("tiny_gs", {"seed=2"}), test::host());
  EXPECT_GT((a.groundTruth()[100].p_W_B - b.groundTruth()[100].p_W_B).norm(), 1e-3);
  EXPECT_GT((a.imu()[100].gyro_rad_s - b.imu()[100].gyro_rad_s).norm(), 1e-3);
  a.prepareRendering();
  b.prepareRendering();
  EXPECT_GT(cv::norm(a.renderImage(3), b.renderImage(3), cv::NORM_L1) / (320.0 * 256.0), 5.0);
}

// One seed with and without a rolling shutter: same stamps, IMU, ground truth and noise; the images
// differ only through the shutter.
TEST(Simulator, RollingShutterPairDiffersOnlyInTheShutter) {
  Simulator gs(test::tinyConfig("tiny_gs"), test::host());
  Simulator rs(test::tinyConfig("tiny_rs"), test::host());
  Simulator rs0(test::tinyConfig("tiny_rs", {"effects.rolling_shutter.params.line_delay_us=0"}), test::host());
  ASSERT_EQ(gs.frameStamps(), rs.frameStamps());
  ASSERT_EQ(gs.imu().size(), rs.imu().size());
  for (size_t k = 0; k < gs.imu().size(); ++k) {
    ASSERT_EQ(gs.imu()[k].gyro_rad_s, rs.imu()[k].gyro_rad_s);
    ASSERT_EQ(gs.imu()[k].accel_m_s2, rs.imu()[k].accel_m_s2);
    ASSERT_EQ(gs.groundTruth()[k].p_W_B, rs.groundTruth()[k].p_W_B);
    ASSERT_EQ(gs.groundTruth()[k].gyro_bias, rs.groundTruth()[k].gyro_bias);
  }
  gs.prepareRendering();
  rs.prepareRendering();
  rs0.prepareRendering();
  const size_t f = 20;
  // A rolling shutter with zero line delay is the global shutter, noise included, bit for bit.
  EXPECT_EQ(maxAbsDiff(gs.renderSignal(f), rs0.renderSignal(f)), 0.0);
  // With the real line delay, rows next to y0 are (almost) the same, far rows are not.
  const cv::Mat a = gs.renderImage(f), b = rs.renderImage(f);
  cv::Mat diff;
  cv::absdiff(a, b, diff);
  const double mid = cv::mean(diff.rowRange(127, 129))[0], top = cv::mean(diff.rowRange(0, 20))[0];
  EXPECT_LT(mid, 3.0);
  EXPECT_GT(top, 3.0 * mid + 2.0);
}

TEST(Simulator, TimeOffsetShiftsCaptureNotStamps) {
  // 50 ms is one frame period: the image stamped like frame k shows what frame k + 1 shows without it.
  Simulator plain(withEffects("tiny_gs", kNoEffects), test::host());
  Simulator shifted(withEffects("tiny_gs", {{"time_offset", effect("effect.time_offset", {{"offset_ms", 50.0}})}}),
                    test::host());
  ASSERT_EQ(plain.frameStamps(), shifted.frameStamps());
  EXPECT_DOUBLE_EQ(shifted.sensor().time_offset_s, 0.05);
  EXPECT_EQ(shifted.sensor().camera.time_offset_s, 0.0);  // never in the calibration
  EXPECT_NEAR(shifted.captureTime(7) - plain.captureTime(7), 0.05, 1e-12);
  plain.prepareRendering();
  shifted.prepareRendering();
  EXPECT_LT(maxAbsDiff(shifted.renderSignal(7), plain.renderSignal(8)), 1e-6);
  EXPECT_GT(maxAbsDiff(shifted.renderSignal(7), plain.renderSignal(7)), 0.05);
  EXPECT_EQ(plain.imu()[50].gyro_rad_s, shifted.imu()[50].gyro_rad_s);
}

TEST(Simulator, ExposureGainMultipliesTheSignal) {
  Simulator plain(withEffects("tiny_gs", kNoEffects), test::host());
  Simulator exposed(withEffects("tiny_gs", {{"exposure", effect("effect.exposure", {{"amplitude_stops", 1.0}, {"period_s", 2.0}})}}),
                    test::host());
  plain.prepareRendering();
  exposed.prepareRendering();
  std::vector<double> gains;
  for (size_t f : {size_t(3), size_t(12), size_t(25)}) {
    nlohmann::json truth;
    const cv::Mat a = plain.renderSignal(f), b = exposed.renderSignal(f, &truth);
    const double g = truth.at("exposure").at("gain").get<double>();
    EXPECT_NEAR(cv::sum(b)[0] / cv::sum(a)[0], g, 1e-5 * g);
    gains.push_back(g);
  }
  EXPECT_GT(*std::max_element(gains.begin(), gains.end()) / *std::min_element(gains.begin(), gains.end()), 1.5);
}

TEST(Simulator, VignettingCornerToCentreRatio) {
  Simulator plain(withEffects("tiny_gs", kNoEffects), test::host());
  Simulator vig(withEffects("tiny_gs", {{"vignette", effect("effect.vignette", {{"k1", -0.3}, {"k2", -0.15}, {"k3", -0.05}})}}),
                test::host());
  plain.prepareRendering();
  vig.prepareRendering();
  const cv::Mat a = plain.renderSignal(5), b = vig.renderSignal(5);
  cv::Mat ratio;
  cv::divide(b, a, ratio);
  // cx, cy = 159.5, 127.5 is the centre: every corner is a farthest corner, V = 1 + k1 + k2 + k3.
  for (const cv::Point& corner : {cv::Point(0, 0), cv::Point(319, 0), cv::Point(0, 255), cv::Point(319, 255)})
    EXPECT_NEAR(ratio.at<float>(corner), 0.5, 1e-5);
  EXPECT_NEAR(ratio.at<float>(127, 159), 1.0, 1e-4);
}

TEST(Simulator, ResponseCurveMapsTheLinearSignal) {
  Simulator plain(withEffects("tiny_gs", kNoEffects), test::host());
  Simulator curved(withEffects("tiny_gs", {{"response", effect("effect.response", {{"model", "gamma"}, {"gamma", 2.2}})}}),
                   test::host());
  plain.prepareRendering();
  curved.prepareRendering();
  const cv::Mat a = plain.renderSignal(4), b = curved.renderSignal(4);
  for (int y = 0; y < a.rows; y += 17)
    for (int x = 0; x < a.cols; x += 13)
      ASSERT_NEAR(b.at<float>(y, x), std::pow(std::clamp(a.at<float>(y, x), 0.0f, 1.0f), 1.0 / 2.2), 1e-5);
}

TEST(Simulator, ImageNoiseHasTheParametersStd) {
  Simulator plain(withEffects("tiny_gs", kNoEffects), test::host());
  Simulator noisy(withEffects("tiny_gs", {{"image_noise", effect("effect.image_noise", {{"read_noise_dn", 2.0}, {"full_well_e", 0.0}})}}),
                  test::host());
  plain.prepareRendering();
  noisy.prepareRendering();
  cv::Mat d = noisy.renderSignal(9) - plain.renderSignal(9);
  cv::Scalar mean, stddev;
  cv::meanStdDev(d, mean, stddev);
  EXPECT_NEAR(stddev[0] * 255.0, 2.0, 0.05);
  EXPECT_NEAR(mean[0] * 255.0, 0.0, 0.05);
  // Another frame gets other noise.
  const cv::Mat d2 = noisy.renderSignal(10) - plain.renderSignal(10);
  EXPECT_GT(maxAbsDiff(d(cv::Rect(0, 0, 50, 50)), d2(cv::Rect(0, 0, 50, 50))), 1e-3);
}

double gradientEnergy(const cv::Mat& img) {
  cv::Mat dx = img.colRange(1, img.cols) - img.colRange(0, img.cols - 1);
  return cv::norm(dx, cv::NORM_L2SQR);
}

TEST(Simulator, MotionBlurSmoothsImagesUnderFastMotion) {
  const std::vector<std::string> fast = {"motion.mean_rot_speed_deg_s=137", "motion.mean_rot_accel_deg_s2=539"};
  Simulator sharp(withEffects("tiny_gs", kNoEffects, fast), test::host());
  Simulator blurred(withEffects("tiny_gs", {{"blur", effect("effect.motion_blur", {{"exposure_ms", 10.0}, {"samples", 8}})}}, fast),
                    test::host());
  EXPECT_DOUBLE_EQ(blurred.sensor().exposure_s, 0.01);
  sharp.prepareRendering();
  blurred.prepareRendering();
  const cv::Mat a = sharp.renderSignal(15), b = blurred.renderSignal(15);
  EXPECT_LT(gradientEnergy(b), 0.9 * gradientEnergy(a));
  EXPECT_NEAR(cv::mean(b)[0], cv::mean(a)[0], 0.02);
}

// Distortion goes to the calibration, and the simulator's raw pixels agree with the estimator's
// camera.pinhole model: the ray through a raw pixel hits a point that camera.pinhole projects back there.
TEST(Simulator, DistortionAgreesWithTheCameraPlugin) {
  for (const std::string model : {"radtan", "equidistant"}) {
    Simulator sim(withEffects("tiny_gs", {{"distortion", effect("effect.distortion", {{"model", model}})}}), test::host());
    const CameraCalibration& cal = sim.sensor().camera;
    EXPECT_EQ(cal.distortion, model);
    EXPECT_EQ(cal.distortion_coeffs.size(), 4);
    auto& host = test::host();
    std::vector<ConfigProblem> problems;
    const nlohmann::json params = validateParams(nlohmann::json::object(), host.info("camera.pinhole").params, "camera", problems);
    ASSERT_TRUE(problems.empty());
    auto camera = host.create<CameraModel>("camera.pinhole", Params(params));
    camera->setCalibration(cal);
    sim.prepareRendering();
    const double t = sim.captureTime(12);
    const Eigen::Isometry3d T_C_W = sim.renderer().T_W_C(t).inverse();
    for (const Vec2 uv : {Vec2(3, 4), Vec2(310, 250), Vec2(160, 20), Vec2(77.25, 190.5)}) {
      Scene::Hit hit;
      ASSERT_TRUE(sim.renderer().castPixel(uv, t, hit));
      Vec2 back;
      ASSERT_TRUE(camera->project(Vec3(T_C_W * hit.p), back));
      EXPECT_NEAR((back - uv).norm(), 0.0, 1e-6) << model << " at " << uv.transpose();
    }
  }
}

TEST(Simulator, HiddenEffectsStayOutOfTheCalibration) {
  Simulator sim(withEffects("tiny_gs", {{"rs", effect("effect.rolling_shutter")},
                                        {"offset", effect("effect.time_offset")},
                                        {"vignette", effect("effect.vignette")}}),
                test::host());
  EXPECT_GT(sim.sensor().line_delay_s, 0.0);
  EXPECT_EQ(sim.sensor().camera.line_delay_s, 0.0);
  EXPECT_EQ(sim.sensor().camera.time_offset_s, 0.0);
  EXPECT_EQ(sim.sensor().camera.distortion, "none");
  const nlohmann::json truth = sim.truth(nlohmann::json::array());
  EXPECT_GT(truth.at("camera").at("line_delay_s").get<double>(), 0.0);
  EXPECT_EQ(truth.at("effects").size(), 3u);
}

std::string configError(const std::vector<std::string>& sets, const std::string& name = "tiny_gs") {
  try {
    test::tinyConfig(name, sets);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

bool has(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

TEST(SimConfig, BadConfigsGivePathNamedErrors) {
  std::string e = configError({"camera.widht_px=300"});
  EXPECT_TRUE(has(e, "camera.widht_px") && has(e, "did you mean \"width_px\"")) << e;
  e = configError({"motion.duration_s=\"long\""});
  EXPECT_TRUE(has(e, "motion.duration_s") && has(e, "expected a number")) << e;
  e = configError({"effects.rolling_shutter.plugin=effect.rolling_shuter"}, "tiny_rs");
  EXPECT_TRUE(has(e, "effects.rolling_shutter.plugin") && has(e, "effect.rolling_shutter")) << e;
  e = configError({"effects.rolling_shutter.params.line_delay=50"}, "tiny_rs");
  EXPECT_TRUE(has(e, "effects.rolling_shutter.params.line_delay") && has(e, "line_delay_us")) << e;
  e = configError({"camera.bit_depth=12"});
  EXPECT_TRUE(has(e, "camera.bit_depth") && has(e, "8 or 16")) << e;
  e = configError({"camera.cx_px=400"});
  EXPECT_TRUE(has(e, "camera.cx_px")) << e;
  e = configError({"motion.wall_clearance_m=4"});
  EXPECT_TRUE(has(e, "motion.wall_clearance_m")) << e;
  e = configError({"effects.camera={\"plugin\": \"camera.pinhole\"}"});
  EXPECT_TRUE(has(e, "effects.camera.plugin")) << e;
  EXPECT_TRUE(has(configError({"scenery.furniture=3"}), "did you mean \"scene\"")) << configError({"scenery.furniture=3"});
  EXPECT_EQ(configError({}), "");
}

TEST(SimConfig, EffectsThatDoNotFitTheMarginAreErrors) {
  try {
    // 95 ms of offset plus half of a 30 ms readout reach 110 ms past the 100 ms margin.
    Simulator sim(withEffects("tiny_gs", {{"offset", effect("effect.time_offset", {{"offset_ms", 95.0}})},
                                          {"rs", effect("effect.rolling_shutter", {{"line_delay_us", 117.88}})}}),
                  test::host());
    FAIL() << "expected a ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_TRUE(has(e.what(), "output.frame_margin_s")) << e.what();
  }
}

TEST(SimConfig, DefaultEffectsAreTheNoises) {
  nlohmann::json c = loadConfigWithSets(test::simConfigPath("tiny_gs"), {});
  c.erase("effects");
  const nlohmann::json e = validateSimConfig(c, test::host(), "x");
  EXPECT_EQ(e.at("effects").size(), 2u);
  EXPECT_TRUE(e.at("effects").contains("image_noise"));
  EXPECT_TRUE(e.at("effects").contains("imu_noise"));
}

}  // namespace
}  // namespace rsvio::sim
