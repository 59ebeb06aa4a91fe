// camera.pinhole through the plugin host: calibration checks and their messages, aliases, the
// min_depth_m parameter and its validation.
#include <gtest/gtest.h>

#include "support/plugin_contracts.h"

namespace rsvio::test {
namespace {

CameraCalibration radtanCalib() {
  CameraCalibration c = defaultContractCalibration();
  c.distortion = "radtan";
  c.distortion_coeffs = Eigen::Vector4d(-0.28, 0.07, 2e-4, -1.5e-4);
  return c;
}

std::string configErrorOf(const CameraCalibration& c) {
  auto cam = makePlugin<CameraModel>("camera.pinhole");
  try {
    cam->setCalibration(c);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(PinholeCamera, InfoAndParamTable) {
  const PluginInfo& info = contractHost().info("camera.pinhole");
  EXPECT_EQ(info.kind, PluginKind::Camera);
  ASSERT_EQ(info.params.size(), 1u);
  EXPECT_EQ(info.params[0].key, "min_depth_m");
  EXPECT_EQ(info.params[0].unit, "m");
  EXPECT_EQ(info.params[0].default_value.get<double>(), 1e-3);
}

TEST(PinholeCamera, CalibrationErrorsNameWhatIsWrong) {
  CameraCalibration c = radtanCalib();
  c.distortion = "kannala_brandt8";
  EXPECT_EQ(configErrorOf(c),
            "camera.pinhole: calibration distortion \"kannala_brandt8\" is not supported (allowed: none, radtan, "
            "equidistant)");
  c = radtanCalib();
  c.projection = "omni";
  EXPECT_NE(configErrorOf(c).find("projection \"omni\""), std::string::npos);
  c = radtanCalib();
  c.distortion_coeffs = Eigen::Vector3d(0.1, 0.2, 0.3);
  EXPECT_NE(configErrorOf(c).find("needs 4 coefficients, found 3"), std::string::npos) << configErrorOf(c);
  c = radtanCalib();
  c.distortion_coeffs.resize(5);
  c.distortion_coeffs << -0.28, 0.07, 2e-4, -1.5e-4, 0.01;  // OpenCV k3 != 0: not representable
  EXPECT_NE(configErrorOf(c).find("needs 4 coefficients, found 5"), std::string::npos);
  c.distortion_coeffs[4] = 0.0;
  EXPECT_EQ(configErrorOf(c), "");
  c = defaultContractCalibration();
  c.distortion_coeffs = Eigen::Vector4d(0.1, 0, 0, 0);
  EXPECT_NE(configErrorOf(c).find("\"none\" has non-zero coefficients"), std::string::npos);
  c = defaultContractCalibration();
  c.distortion_coeffs = Eigen::Vector4d::Zero();  // zero padding is fine
  EXPECT_EQ(configErrorOf(c), "");
  c.intrinsics[0] = 0.0;
  EXPECT_NE(configErrorOf(c).find("fx, fy > 0"), std::string::npos);
  c = defaultContractCalibration();
  c.width = 0;
  EXPECT_NE(configErrorOf(c).find("image size"), std::string::npos);
}

TEST(PinholeCamera, AliasesMeanTheSameModel) {
  const Vec3 p(0.4, -0.3, 1.2);
  const auto projectWith = [&](const std::string& name, const Eigen::VectorXd& k) {
    CameraCalibration c = defaultContractCalibration();
    c.distortion = name;
    c.distortion_coeffs = k;
    auto cam = makePlugin<CameraModel>("camera.pinhole");
    cam->setCalibration(c);
    Vec2 uv;
    EXPECT_TRUE(cam->project(p, uv));
    return uv;
  };
  const Eigen::Vector4d k_rt(-0.28, 0.07, 2e-4, -1.5e-4), k_eq(0.0035, 0.0067, -0.0087, 0.0029);
  EXPECT_EQ(projectWith("radtan", k_rt), projectWith("radial-tangential", k_rt));
  EXPECT_EQ(projectWith("radtan", k_rt), projectWith("plumb_bob", k_rt));
  EXPECT_EQ(projectWith("equidistant", k_eq), projectWith("fisheye", k_eq));
  EXPECT_GT((projectWith("radtan", k_rt) - projectWith("none", Eigen::VectorXd())).norm(), 1.0);
}

TEST(PinholeCamera, MinDepthParam) {
  auto cam = makePlugin<CameraModel>("camera.pinhole", {{"min_depth_m", 0.05}});
  cam->setCalibration(radtanCalib());
  Vec2 uv;
  EXPECT_FALSE(cam->project(Vec3(0.0, 0.0, 0.04), uv));
  EXPECT_TRUE(cam->project(Vec3(0.0, 0.0, 0.06), uv));
}

TEST(PinholeCamera, ParamsAreValidatedLikeAConfigSlot) {
  try {
    makePlugin<CameraModel>("camera.pinhole", {{"min_depth_m", -1.0}, {"min_depht_m", 1.0}});
    FAIL() << "invalid params accepted";
  } catch (const ConfigError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("camera.pinhole.params.min_depth_m"), std::string::npos) << msg;
    EXPECT_NE(msg.find("did you mean"), std::string::npos) << msg;
  }
}

TEST(PinholeCamera, UseBeforeCalibrationIsAnError) {
  auto cam = makePlugin<CameraModel>("camera.pinhole");
  Vec2 uv;
  EXPECT_THROW(cam->project(Vec3(0, 0, 1), uv), Error);
}

}  // namespace
}  // namespace rsvio::test
