// shutter.rolling and shutter.global through the plugin host: where the line delay and readout come
// from (param over calibration), the error when neither knows a line delay, and param validation.
#include <gtest/gtest.h>

#include <cmath>

#include "support/plugin_contracts.h"

namespace rsvio::test {
namespace {

CameraCalibration calibWithout() {
  CameraCalibration c = defaultContractCalibration();
  c.line_delay_s = 0.0;  // as calibration files usually are
  return c;
}

TEST(RollingShutter, NoLineDelayAnywhereIsAConfigError) {
  auto s = makePlugin<ShutterModel>("shutter.rolling");
  try {
    s->setCalibration(calibWithout());
    FAIL() << "accepted a rolling shutter without a line delay";
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()), "shutter.rolling needs line_delay_us: the calibration has no line delay; give it "
                                     "with --set shutter.params.line_delay_us=<microseconds per row> (readout time / "
                                     "image rows), or estimate it with --set shutter.params.estimate_line_delay=true");
  }
}

// estimate_line_delay: no delay anywhere is fine, the estimate starts from 0 and the readout direction
// is kept in the sign bit of the zero derivative (-0.0 bottom_up), so RowTiming knows it.
TEST(RollingShutter, EstimatedLineDelayMayStartFromZero) {
  for (const char* readout : {"top_down", "bottom_up"}) {
    auto s = makePlugin<ShutterModel>("shutter.rolling", {{"estimate_line_delay", true}, {"readout", readout}});
    s->setCalibration(calibWithout());
    EXPECT_TRUE(s->estimatesLineDelay());
    EXPECT_EQ(s->lineDelay(), 0.0);
    EXPECT_EQ(std::signbit(s->rowTimeDerivative()), std::string(readout) == "bottom_up") << readout;
  }
  auto given = makePlugin<ShutterModel>("shutter.rolling", {{"estimate_line_delay", true}, {"line_delay_us", 40.0}});
  given->setCalibration(calibWithout());
  EXPECT_DOUBLE_EQ(given->lineDelay(), 40e-6);  // the start
  EXPECT_FALSE(makePlugin<ShutterModel>("shutter.rolling", {{"line_delay_us", 40.0}})->estimatesLineDelay());
}

TEST(RollingShutter, ParamLineDelayIsUsedWhenTheCalibrationHasNone) {
  auto s = makePlugin<ShutterModel>("shutter.rolling", {{"line_delay_us", 29.5}});
  const CameraCalibration c = calibWithout();
  s->setCalibration(c);
  EXPECT_TRUE(s->isRolling());
  EXPECT_DOUBLE_EQ(s->lineDelay(), 29.5e-6);
  EXPECT_DOUBLE_EQ(s->rowTime(c.rowZero() + 10.0), 10.0 * 29.5e-6);
}

TEST(RollingShutter, ParamWinsOverCalibrationAndCalibrationIsTheDefault) {
  CameraCalibration c = defaultContractCalibration();
  c.line_delay_s = 15e-6;
  auto from_calib = makePlugin<ShutterModel>("shutter.rolling");
  from_calib->setCalibration(c);
  EXPECT_DOUBLE_EQ(from_calib->lineDelay(), 15e-6);
  auto from_param = makePlugin<ShutterModel>("shutter.rolling", {{"line_delay_us", 40.0}});
  from_param->setCalibration(c);
  EXPECT_DOUBLE_EQ(from_param->lineDelay(), 40e-6);
}

TEST(RollingShutter, Readout) {
  CameraCalibration c = defaultContractCalibration();
  c.readout = "bottom_up";
  auto from_calib = makePlugin<ShutterModel>("shutter.rolling");
  from_calib->setCalibration(c);
  EXPECT_LT(from_calib->rowTimeDerivative(), 0.0);
  EXPECT_GT(from_calib->rowTime(0.0), 0.0);  // bottom-up: the top row is read last
  auto forced = makePlugin<ShutterModel>("shutter.rolling", {{"readout", "top_down"}});
  forced->setCalibration(c);
  EXPECT_GT(forced->rowTimeDerivative(), 0.0);
  c.readout = "left_right";
  auto bad = makePlugin<ShutterModel>("shutter.rolling");
  try {
    bad->setCalibration(c);
    FAIL() << "accepted readout left_right";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("\"left_right\""), std::string::npos) << e.what();
  }
}

TEST(RollingShutter, SetLineDelayRefusesNegativeOrNonFinite) {
  auto s = makePlugin<ShutterModel>("shutter.rolling", {{"line_delay_us", 20.0}});
  s->setCalibration(calibWithout());
  EXPECT_THROW(s->setLineDelay(-1e-6), Error);
  EXPECT_THROW(s->setLineDelay(std::nan("")), Error);
  EXPECT_DOUBLE_EQ(s->lineDelay(), 20e-6);
  s->setLineDelay(0.0);  // allowed during estimation
  EXPECT_EQ(s->rowTime(0.0), 0.0);
}

TEST(RollingShutter, ParamsAreValidatedLikeAConfigSlot) {
  try {
    makePlugin<ShutterModel>("shutter.rolling", {{"line_delay_us", -3.0}, {"readout", "sideways"}});
    FAIL() << "invalid params accepted";
  } catch (const ConfigError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("shutter.rolling.params.line_delay_us"), std::string::npos) << msg;
    EXPECT_NE(msg.find("shutter.rolling.params.readout"), std::string::npos) << msg;
    EXPECT_NE(msg.find("top_down"), std::string::npos) << msg;
  }
}

TEST(GlobalShutter, IsNotRollingWhateverTheCalibrationSays) {
  auto s = makePlugin<ShutterModel>("shutter.global");
  s->setCalibration(defaultContractCalibration());  // has a line delay: ignored
  EXPECT_FALSE(s->isRolling());
  EXPECT_EQ(s->rowTime(0.0), 0.0);
  EXPECT_THROW(makePlugin<ShutterModel>("shutter.global", {{"line_delay_us", 3.0}}), ConfigError);
}

}  // namespace
}  // namespace rsvio::test
