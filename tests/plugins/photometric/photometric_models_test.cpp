// photometric.affine, photometric.vignette and photometric.response: corrections with a calibration,
// online parameters and their derivatives without one, errors naming the slot or file, and loading
// through the plugin host.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "plugins/photometric/response/response_model.h"
#include "plugins/photometric/vignette/vignette_model.h"
#include "rsvio/config/validate.h"
#include "rsvio/photometric/vignette_fit.h"
#include "rsvio/plugin/host.h"
#include "support/numeric_jacobian.h"

namespace rsvio {
namespace {

SensorSetup sensors(int w = 40, int h = 30) {
  SensorSetup s;
  s.camera.width = w;
  s.camera.height = h;
  s.camera.intrinsics << 30, 30, 19.5, 14.5;
  return s;
}

Frame frame() {
  Frame f;
  f.index = 1;
  return f;
}

TEST(VignetteModel, CalibratedDividesByTheVignette) {
  SensorSetup s = sensors();
  s.photometric.vignette = cv::Mat(30, 40, CV_32F, cv::Scalar(0.5));
  s.photometric.vignette.at<float>(3, 4) = 0.01f;  // clamped to min_value
  VignetteModel m(VignetteModel::Mode::Auto, 0.05, Eigen::Vector3d::Zero());
  m.setSensors(s);
  EXPECT_TRUE(m.isCalibrated());
  EXPECT_EQ(m.numParams(), 0);
  cv::Mat img(30, 40, CV_32F, cv::Scalar(60.0));
  m.correct(img, frame());
  EXPECT_FLOAT_EQ(img.at<float>(10, 10), 120.f);
  EXPECT_FLOAT_EQ(img.at<float>(3, 4), 60.f / 0.05f);
  double dv = 0;
  EXPECT_DOUBLE_EQ(m.predict(7.0, Vec2(1, 2), &dv, nullptr), 7.0);
  EXPECT_DOUBLE_EQ(dv, 1.0);
}

// Residual rows of images corrected with `applied` while the truth is `truth` (interfaces/photometric.h,
// rsvio/photometric/vignette_fit.h): r = I (W(rho_t) / W(rho_h) - 1), W = truth / applied, each pair
// with a gain and offset of its own; radii normalised by the half diagonal, as the log's.
std::vector<ObservationRow> vignetteRows(const Eigen::Vector3d& truth, const Eigen::Vector3d& applied,
                                         double to_model_rho, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 1.5);
  const auto W = [&](double rho) { return vignetteValue(truth, rho) / vignetteValue(applied, rho); };
  std::vector<ObservationRow> rows;
  for (int pair = 0; pair < 40; ++pair) {
    const double gain = 0.9 + 0.2 * U(rng), offset = 10.0 * (U(rng) - 0.5);
    for (int k = 0; k < 100; ++k) {
      ObservationRow o;
      o.frame = 10 + pair;
      o.host = 5 + pair;
      const double rt = U(rng), rh = U(rng);  // model radii
      o.radius = static_cast<float>(rt / to_model_rho);
      o.host_radius = static_cast<float>(rh / to_model_rho);
      o.intensity = static_cast<float>(30.0 + 200.0 * U(rng));
      o.residual = static_cast<float>(gain * o.intensity * W(rt) / W(rh) + offset - o.intensity + noise(rng));
      o.weight = k % 10 == 0 ? 0.f : 1.f;  // some dropped as outliers
      rows.push_back(o);
    }
  }
  return rows;
}

// The fit's Jacobian (rsvio/photometric/vignette_fit.h) against central differences, at a few
// observations spread over the radii.
TEST(VignetteFit, ResidualJacobianMatchesNumericDifferences) {
  const Eigen::Vector3d k(-0.3, -0.15, -0.05);
  for (const auto& [rt, rh] : std::vector<std::pair<double, double>>{{0.1, 0.9}, {0.5, 0.5}, {1.0, 0.3}, {0.7, 0.0}}) {
    Eigen::Vector3d J;
    vignetteResidual(k, 120.0, rt, rh, &J);
    const Eigen::MatrixXd num = test::numericJacobian(
        [&](const Eigen::VectorXd& kk) { return vignetteResidual(Eigen::Vector3d(kk), 120.0, rt, rh, nullptr); },
        Eigen::VectorXd(k), test::vectorPlus, 3);
    EXPECT_JACOBIAN_NEAR(J.transpose(), num, 1e-6) << "rho_t " << rt << " rho_h " << rh;
  }
}

TEST(VignetteModel, EstimatedOnlineDividesByThePolynomialAndRefinesItFromResiduals) {
  const Eigen::Vector3d initial(-0.1, 0.0, 0.0), truth(-0.3, -0.15, -0.05);
  VignetteModel m(VignetteModel::Mode::Auto, 0.05, initial, "photometric.vignette", /*min_rows=*/1000);
  m.setSensors(sensors());
  EXPECT_FALSE(m.isCalibrated());
  EXPECT_TRUE(m.estimatesOnline());
  ASSERT_EQ(m.numParams(), 3);
  EXPECT_EQ(m.minRowsForRefine(), 1000u);
  EXPECT_DOUBLE_EQ(m.radius(Vec2(19.5, 14.5)), 0.0);
  EXPECT_DOUBLE_EQ(m.radius(Vec2(0, 0)), 1.0);  // farthest corner
  cv::Mat img(30, 40, CV_32F, cv::Scalar(60.0));
  m.correct(img, frame());
  EXPECT_FLOAT_EQ(img.at<float>(0, 0), static_cast<float>(60.0 / 0.9));  // divided by V(1) = 0.9
  EXPECT_FLOAT_EQ(img.at<float>(14, 19), static_cast<float>(60.0 / m.vignette(Vec2(19, 14))));
  double dv = 0;
  EXPECT_DOUBLE_EQ(m.predict(7.0, Vec2(1, 2), &dv, nullptr), 7.0);  // the images carry the correction
  EXPECT_DOUBLE_EQ(dv, 1.0);

  // The rows' radii (half diagonal 25 px) against the model's (farthest corner, 24.3 px).
  const double to_model = 0.5 * std::hypot(40.0, 30.0) / std::hypot(19.5, 14.5);
  std::string note;
  ASSERT_TRUE(m.refineFromResiduals(vignetteRows(truth, initial, to_model, 1), &note));
  EXPECT_FALSE(note.empty());
  EXPECT_EQ(m.updates(), 1);
  const Eigen::Vector3d k = m.params();
  for (double rho : {0.25, 0.5, 0.75, 1.0})
    EXPECT_NEAR(vignetteValue(k, rho), vignetteValue(truth, rho), 0.02) << "rho " << rho;
  // setParams (and a refinement) changes what correct() divides by.
  cv::Mat img2(30, 40, CV_32F, cv::Scalar(60.0));
  m.correct(img2, frame());
  EXPECT_NEAR(img2.at<float>(0, 0), 60.0 / vignetteValue(k, 1.0), 1e-3);
  // Residuals with nothing left (only noise and pair gains) change nothing; nor do too few rows.
  EXPECT_FALSE(m.refineFromResiduals(vignetteRows(truth, truth, to_model, 2), &note));
  std::vector<ObservationRow> few = vignetteRows(truth, initial, to_model, 3);
  few.resize(900);
  EXPECT_FALSE(m.refineFromResiduals(few, &note));
  EXPECT_EQ(m.updates(), 1);
  EXPECT_EQ(Eigen::Vector3d(m.params()), k);
}

TEST(VignetteModel, AnImplausiblePolynomialIsAConfigErrorNamingTheKey) {
  for (const auto mode : {VignetteModel::Mode::Fixed, VignetteModel::Mode::Estimate}) {
    VignetteModel m(mode, 0.05, Eigen::Vector3d(-1.2, 0.0, 0.0), "photometric.v");
    try {
      m.setSensors(sensors());
      FAIL() << "no error";
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find("photometric.v.params.initial"), std::string::npos) << e.what();
    }
  }
}

TEST(VignetteModel, FixedDividesByThePolynomialAndIsNotEstimated) {
  VignetteModel m(VignetteModel::Mode::Fixed, 0.05, Eigen::Vector3d(-0.2, 0.0, 0.0));
  m.setSensors(sensors());
  EXPECT_TRUE(m.isCalibrated());
  EXPECT_FALSE(m.estimatesOnline());
  EXPECT_EQ(m.numParams(), 0);
  cv::Mat img(30, 40, CV_32F, cv::Scalar(60.0));
  m.correct(img, frame());
  EXPECT_FLOAT_EQ(img.at<float>(0, 0), static_cast<float>(60.0 / 0.8));
  EXPECT_FALSE(m.refineFromResiduals(vignetteRows(Eigen::Vector3d(-0.3, 0, 0), Eigen::Vector3d(-0.2, 0, 0),
                                                  1.0, 1),
                                     nullptr));
}

TEST(VignetteModel, ErrorsNameTheSlotAndFile) {
  VignetteModel m(VignetteModel::Mode::Calibrated, 0.05, Eigen::Vector3d::Zero(), "photometric.vig");
  try {
    m.setSensors(sensors());
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("photometric.vig.params.mode"), std::string::npos) << e.what();
  }
  SensorSetup s = sensors();
  s.photometric.vignette = cv::Mat(10, 10, CV_32F, cv::Scalar(1.0));
  s.photometric.vignette_path = "/data/vignette.png";
  try {
    m.setSensors(s);
    FAIL();
  } catch (const DataError& e) {
    EXPECT_NE(std::string(e.what()).find("/data/vignette.png"), std::string::npos) << e.what();
  }
  VignetteModel est(VignetteModel::Mode::Estimate, 0.05, Eigen::Vector3d::Zero());
  s.photometric.vignette = cv::Mat(30, 40, CV_32F, cv::Scalar(0.5));
  est.setSensors(s);
  EXPECT_FALSE(est.isCalibrated());  // "estimate" ignores the file on purpose
}

TEST(ResponseModel, CalibratedInverseResponseIsRescaledAndInterpolated) {
  SensorSetup s = sensors();
  s.photometric.inverse_response.resize(256);
  for (int i = 0; i < 256; ++i) s.photometric.inverse_response[i] = 10.f + 2.f * i * i / 255.f;  // convex
  ResponseModel m(ResponseModel::Mode::Auto, 1.0);
  m.setSensors(s);
  ASSERT_TRUE(m.isCalibrated());
  EXPECT_FLOAT_EQ(m.inverse(0.f), 0.f);
  EXPECT_FLOAT_EQ(m.inverse(255.f), 255.f);
  EXPECT_NEAR(m.inverse(100.f), 255.f * 100.f * 100.f / (255.f * 255.f), 1e-3);
  EXPECT_NEAR(m.inverse(100.5f), 0.5f * (m.inverse(100.f) + m.inverse(101.f)), 1e-4);
  cv::Mat img(30, 40, CV_32F, cv::Scalar(100.0));
  m.correct(img, frame());
  EXPECT_FLOAT_EQ(img.at<float>(5, 5), m.inverse(100.f));
  EXPECT_EQ(m.numParams(), 0);
}

TEST(ResponseModel, EstimatedGammaAndItsDerivatives) {
  ResponseModel m(ResponseModel::Mode::Auto, 1.0);
  m.setSensors(sensors());
  ASSERT_EQ(m.numParams(), 1);
  Eigen::VectorXd g(1);
  g << 0.6;
  m.setParams(g);
  const double B = 90.0;
  double d_value = 0;
  Eigen::VectorXd d_params;
  const double I = m.predict(B, Vec2(3, 3), &d_value, &d_params);
  EXPECT_NEAR(I, 255.0 * std::pow(B / 255.0, 0.6), 1e-12);
  const Eigen::MatrixXd num_g = test::numericJacobian(
      [&](const Eigen::VectorXd& p) {
        ResponseModel mm = m;
        mm.setParams(p);
        return mm.predict(B, Vec2(3, 3), nullptr, nullptr);
      },
      Eigen::VectorXd(m.params()), test::vectorPlus, 1);
  EXPECT_JACOBIAN_NEAR(d_params.transpose(), num_g, 1e-7);
  const Eigen::MatrixXd num_v =
      test::numericJacobian([&](double x) { return m.predict(x, Vec2(3, 3), nullptr, nullptr); }, B, test::vectorPlus, 1);
  EXPECT_NEAR(d_value, num_v(0, 0), 1e-7);
  EXPECT_THROW(m.setParams(Eigen::VectorXd::Zero(1)), Error);
}

TEST(ResponseModel, BadCalibrationIsADataError) {
  SensorSetup s = sensors();
  s.photometric.inverse_response.assign(100, 1.f);
  s.photometric.response_path = "/data/pcalib.txt";
  ResponseModel m(ResponseModel::Mode::Auto, 1.0);
  try {
    m.setSensors(s);
    FAIL();
  } catch (const DataError& e) {
    EXPECT_NE(std::string(e.what()).find("/data/pcalib.txt"), std::string::npos);
  }
  ResponseModel c(ResponseModel::Mode::Calibrated, 1.0);
  EXPECT_THROW(c.setSensors(sensors()), ConfigError);
}

Params defaults(PluginHost& host, const std::string& name, const nlohmann::json& given = nlohmann::json::object()) {
  std::vector<ConfigProblem> problems;
  auto p = validateParams(given, host.info(name).params, "photometric.x.params", problems);
  EXPECT_TRUE(problems.empty());
  return Params(p, "photometric.x");
}

TEST(PhotometricPlugins, LoadThroughTheHost) {
  PluginHost host({RSVIO_PLUGIN_DIR});
  auto affine = host.create<PhotometricModel>("photometric.affine", defaults(host, "photometric.affine"));
  EXPECT_TRUE(affine->hasAffineBrightness());
  EXPECT_DOUBLE_EQ(affine->affinePriorA(), 0.0);
  auto affine2 = host.create<PhotometricModel>("photometric.affine",
                                               defaults(host, "photometric.affine", {{"prior_a", 1e12}}));
  EXPECT_DOUBLE_EQ(affine2->affinePriorA(), 1e12);
  auto vig = host.create<PhotometricModel>("photometric.vignette", defaults(host, "photometric.vignette"));
  vig->setSensors(sensors());
  EXPECT_FALSE(vig->hasAffineBrightness());
  EXPECT_EQ(vig->numParams(), 3);
  auto resp = host.create<PhotometricModel>("photometric.response",
                                            defaults(host, "photometric.response", {{"mode", "calibrated"}}));
  try {
    resp->setSensors(sensors());
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("photometric.x.params.mode"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace rsvio
