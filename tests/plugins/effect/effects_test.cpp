// effect.* plugins: one contract suite for all of them, then each effect's parameter doing what it says
// on a controlled input (constant images, ideal IMU streams).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "rsvio/config/validate.h"
#include "rsvio/interfaces/sim_effect.h"
#include "rsvio/plugin/host.h"
#include "rsvio/sim/rng.h"

namespace rsvio {
namespace {

PluginHost& host() {
  static PluginHost h({RSVIO_PLUGIN_DIR});
  return h;
}

std::unique_ptr<SimEffect> make(const std::string& name, const nlohmann::json& params = nlohmann::json::object()) {
  std::vector<ConfigProblem> problems;
  const nlohmann::json full = validateParams(params, host().info(name).params, "params", problems);
  EXPECT_TRUE(problems.empty()) << (problems.empty() ? "" : problems[0].str());
  return host().create<SimEffect>(name, Params(full, "params"));
}

SimSensorModel sensor320() {
  SimSensorModel s;
  s.camera.width = 320;
  s.camera.height = 256;
  s.camera.intrinsics << 208, 208, 159.5, 127.5;
  s.start_ns = 1000;
  return s;
}

const std::vector<std::string> kEffects = {"rolling_shutter", "time_offset", "exposure", "vignette", "response",
                                           "distortion", "image_noise", "motion_blur", "imu_noise", "imu_bias"};

class EffectContract : public ::testing::TestWithParam<std::string> {};

TEST_P(EffectContract, LoadsDocumentsAndBehaves) {
  const std::string name = "effect." + GetParam();
  const PluginInfo& info = host().info(name);
  EXPECT_EQ(info.kind, PluginKind::Effect);
  EXPECT_FALSE(info.description.empty());
  ASSERT_FALSE(info.params.empty());
  // The README beside the code lists every parameter of the table.
  std::ifstream in(std::string(RSVIO_SOURCE_DIR) + "/plugins/effect/" + GetParam() + "/README.md");
  ASSERT_TRUE(in.good()) << "missing README.md for " << name;
  std::stringstream readme;
  readme << in.rdbuf();
  EXPECT_NE(readme.str().find(name), std::string::npos);
  for (const ParamSpec& p : info.params) {
    EXPECT_FALSE(p.description.empty()) << name << "." << p.key;
    EXPECT_FALSE(p.default_value.is_null()) << name << "." << p.key << ": every effect works with its defaults";
    EXPECT_NE(readme.str().find("`" + p.key + "`"), std::string::npos) << name << " README lacks " << p.key;
  }
  // Defaults create it; hooks keep image size/type and are deterministic in the stream.
  auto effect = make(name);
  SimSensorModel s = sensor320();
  effect->configure(s);
  EXPECT_TRUE(effect->truth().is_object());
  cv::Mat a(256, 320, CV_32F, cv::Scalar(0.4)), b = a.clone();
  SimImageContext ctx;
  ctx.sensor = &s;
  ctx.t_cam_ns = 2000000000;
  nlohmann::json ft;
  ctx.frame_truth = &ft;
  std::mt19937_64 r1 = sim::makeStream(1, name, 3), r2 = sim::makeStream(1, name, 3);
  effect->processImage(a, ctx, r1);
  effect->processImage(b, ctx, r2);
  EXPECT_EQ(a.type(), CV_32F);
  EXPECT_EQ(a.size(), cv::Size(320, 256));
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0);
  // Only effects a calibration knows may say so.
  const bool calib = GetParam() == "distortion" || GetParam() == "imu_noise";
  EXPECT_EQ(effect->inCalibration(), calib);
}

INSTANTIATE_TEST_SUITE_P(AllEffects, EffectContract, ::testing::ValuesIn(kEffects));

TEST(Effects, ConfigureOnlyEffectsSetTheSensorModel) {
  SimSensorModel s = sensor320();
  make("effect.rolling_shutter", {{"line_delay_us", 30.0}, {"readout", "bottom_up"}})->configure(s);
  EXPECT_DOUBLE_EQ(s.line_delay_s, 30e-6);
  EXPECT_EQ(s.readout, "bottom_up");
  EXPECT_NEAR(s.rowTime(0.0), 127.5 * 30e-6, 1e-15);  // bottom-up: the top row is read last
  make("effect.time_offset", {{"offset_ms", -7.5}})->configure(s);
  EXPECT_DOUBLE_EQ(s.time_offset_s, -7.5e-3);
  make("effect.motion_blur", {{"exposure_ms", 4.0}, {"samples", 5}})->configure(s);
  EXPECT_DOUBLE_EQ(s.exposure_s, 4e-3);
  EXPECT_EQ(s.blur_samples, 5);
  make("effect.distortion", {{"model", "equidistant"}, {"equidistant_k1_k4", {0.1, 0.01, 0.001, 0.0001}}})->configure(s);
  EXPECT_EQ(s.camera.distortion, "equidistant");
  EXPECT_EQ(s.camera.distortion_coeffs[0], 0.1);
  EXPECT_EQ(s.camera.distortion_coeffs[3], 0.0001);
  EXPECT_EQ(s.camera.line_delay_s, 0.0);
}

TEST(Effects, VignetteCornerRatio) {
  auto v = make("effect.vignette", {{"k1", -0.2}, {"k2", -0.1}, {"k3", 0.0}});
  SimSensorModel s = sensor320();
  v->configure(s);
  cv::Mat img(256, 320, CV_32F, cv::Scalar(0.6));
  std::mt19937_64 rng(1);
  v->processImage(img, SimImageContext{0, 0, 0.0, &s, nullptr}, rng);
  EXPECT_NEAR(img.at<float>(0, 0) / img.at<float>(127, 159), 0.7, 1e-5);
  EXPECT_NEAR(img.at<float>(255, 319) / 0.6, 0.7, 1e-5);
  EXPECT_NEAR(v->truth().at("corner_ratio").get<double>(), 0.7, 1e-12);
  EXPECT_THROW(make("effect.vignette", {{"k1", -1.5}}), ConfigError);  // V(1) < 0
}

TEST(Effects, ExposureGainFollowsItsFormula) {
  auto e = make("effect.exposure", {{"amplitude_stops", 1.0}, {"period_s", 4.0}, {"phase_deg", 0.0}, {"jitter_stops", 0.0}});
  SimSensorModel s = sensor320();
  e->configure(s);
  for (double t : {0.0, 1.0, 3.0}) {
    cv::Mat img(8, 8, CV_32F, cv::Scalar(0.25));
    nlohmann::json ft;
    SimImageContext ctx{0, s.start_ns + static_cast<int64_t>(t * 1e9), t, &s, &ft};
    std::mt19937_64 rng(1);
    e->processImage(img, ctx, rng);
    const double expected = std::exp2(std::sin(2 * M_PI * t / 4.0));  // 1, 2, 0.5
    EXPECT_NEAR(ft.at("gain").get<double>(), expected, 1e-12);
    EXPECT_NEAR(img.at<float>(3, 3), 0.25 * expected, 1e-6);
  }
}

TEST(Effects, ResponseCurves) {
  auto g = make("effect.response", {{"model", "gamma"}, {"gamma", 2.0}});
  auto sc = make("effect.response", {{"model", "s_curve"}, {"contrast", 2.0}});
  cv::Mat img = (cv::Mat_<float>(1, 4) << 0.0f, 0.25f, 0.5f, 1.5f);
  cv::Mat img2 = img.clone();
  std::mt19937_64 rng(1);
  SimSensorModel s = sensor320();
  g->processImage(img, SimImageContext{0, 0, 0.0, &s, nullptr}, rng);
  sc->processImage(img2, SimImageContext{0, 0, 0.0, &s, nullptr}, rng);
  EXPECT_NEAR(img.at<float>(1), 0.5f, 1e-6);
  EXPECT_NEAR(img.at<float>(3), 1.0f, 1e-6);  // saturates
  EXPECT_NEAR(img2.at<float>(1), 0.0625 / (0.0625 + 0.5625), 1e-6);
  EXPECT_NEAR(img2.at<float>(2), 0.5f, 1e-6);
  // The inverse table in truth.json inverts the curve.
  const auto inv = g->truth().at("inverse_response_8bit").get<std::vector<double>>();
  ASSERT_EQ(inv.size(), 256u);
  EXPECT_NEAR(inv[128], 255.0 * std::pow(128.0 / 255.0, 2.0), 1e-9);
}

TEST(Effects, ImageNoiseStd) {
  auto n = make("effect.image_noise", {{"read_noise_dn", 1.0}, {"full_well_e", 1000.0}});
  cv::Mat img(256, 320, CV_32F, cv::Scalar(0.5));
  std::mt19937_64 rng = sim::makeStream(9, "effect.image_noise", 0);
  SimSensorModel s = sensor320();
  n->processImage(img, SimImageContext{0, 0, 0.0, &s, nullptr}, rng);
  cv::Scalar mean, stddev;
  cv::meanStdDev(img, mean, stddev);
  const double expected = std::sqrt(std::pow(1.0 / 255.0, 2) + 0.5 / 1000.0);
  EXPECT_NEAR(stddev[0], expected, 0.02 * expected);
  EXPECT_NEAR(mean[0], 0.5, 3.0 * expected / std::sqrt(320.0 * 256.0));
}

std::vector<ImuSample> flatImu(size_t n) {
  std::vector<ImuSample> v(n);
  for (size_t k = 0; k < n; ++k) {
    v[k].t_ns = static_cast<int64_t>(k) * 5000000;
    v[k].accel_m_s2 = Vec3(0, 0, 9.81);
  }
  return v;
}

TEST(Effects, ImuBiasMean) {
  auto b = make("effect.imu_bias", {{"gyro_bias_rad_s", {0.01, 0.02, -0.03}}, {"accel_bias_m_s2", {0.1, -0.2, 0.3}}});
  auto imu = flatImu(100);
  SimSensorModel s = sensor320();
  SimImuContext ctx;
  ctx.sensor = &s;
  ctx.gyro_bias_rad_s.assign(100, Vec3::Zero());
  ctx.accel_bias_m_s2.assign(100, Vec3::Zero());
  std::mt19937_64 rng(1);
  b->processImu(imu, ctx, rng);
  Vec3 mg = Vec3::Zero(), ma = Vec3::Zero();
  for (const auto& m : imu) mg += m.gyro_rad_s / 100.0, ma += m.accel_m_s2 / 100.0;
  EXPECT_NEAR((mg - Vec3(0.01, 0.02, -0.03)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((ma - Vec3(0.1, -0.2, 9.81 + 0.3)).norm(), 0.0, 1e-12);
  EXPECT_EQ(ctx.accel_bias_m_s2[57], Vec3(0.1, -0.2, 0.3));
}

TEST(Effects, ImuNoiseStdAndSwitches) {
  SimSensorModel s = sensor320();
  s.imu.gyro_noise_density = 0.002;
  s.imu.accel_noise_density = 0.02;
  const size_t n = 20000;
  for (bool walk : {false, true}) {
    auto e = make("effect.imu_noise", {{"bias_random_walk", walk}});
    e->configure(s);
    auto imu = flatImu(n);
    SimImuContext ctx;
    ctx.sensor = &s;
    ctx.gyro_bias_rad_s.assign(n, Vec3::Zero());
    ctx.accel_bias_m_s2.assign(n, Vec3::Zero());
    std::mt19937_64 rng = sim::makeStream(2, "effect.imu_noise");
    e->processImu(imu, ctx, rng);
    double sg = 0;
    for (size_t k = 0; k < n; ++k) sg += (imu[k].gyro_rad_s - ctx.gyro_bias_rad_s[k]).squaredNorm();
    EXPECT_NEAR(std::sqrt(sg / (3.0 * n)), 0.002 * std::sqrt(200.0), 0.03 * 0.002 * std::sqrt(200.0));
    EXPECT_EQ(ctx.gyro_bias_rad_s.back().isZero(), !walk);
  }
}

}  // namespace
}  // namespace rsvio
