// The camera contract (tests/support/plugin_contracts.h) run against every camera plugin the host
// finds, with the calibrations of each plugin's contract.json.
#include <gtest/gtest.h>

#include "support/plugin_contracts.h"

namespace rsvio::test {
namespace {

class CameraContract : public ::testing::TestWithParam<ContractCase> {};

TEST_P(CameraContract, RoundTripOverTheImage) {
  checkCameraRoundTrip(*makeContractPlugin<CameraModel>(GetParam()));
}

TEST_P(CameraContract, JacobiansMatchNumeric) {
  checkCameraJacobians(*makeContractPlugin<CameraModel>(GetParam()));
}

TEST_P(CameraContract, PointsBehindTheCameraAreInvalid) {
  checkCameraInvalidPoints(*makeContractPlugin<CameraModel>(GetParam()));
}

TEST_P(CameraContract, UnknownDistortionIsAConfigErrorNamingIt) { checkCameraRejectsUnknownDistortion(GetParam()); }

INSTANTIATE_TEST_SUITE_P(AllCameraPlugins, CameraContract, ::testing::ValuesIn(contractCases(PluginKind::Camera, true)),
                         contractCaseName);

}  // namespace
}  // namespace rsvio::test
