// The shutter contract (tests/support/plugin_contracts.h) run against every shutter plugin the host
// finds, read top-down and bottom-up, with a calibration that knows its line delay.
#include <gtest/gtest.h>

#include "support/plugin_contracts.h"

namespace rsvio::test {
namespace {

class ShutterContract : public ::testing::TestWithParam<ContractCase> {};

TEST_P(ShutterContract, RowTimeIsZeroAtY0AndLinearWithItsDerivative) {
  for (const char* readout : {"top_down", "bottom_up"}) {
    ContractCase c = GetParam();
    c.calib.readout = readout;
    SCOPED_TRACE(readout);
    checkShutterTiming(*makeContractPlugin<ShutterModel>(c), c.calib);
  }
}

TEST_P(ShutterContract, SetLineDelay) {
  for (const char* readout : {"top_down", "bottom_up"}) {
    ContractCase c = GetParam();
    c.calib.readout = readout;
    SCOPED_TRACE(readout);
    checkShutterSetLineDelay(*makeContractPlugin<ShutterModel>(c), c.calib);
  }
}

INSTANTIATE_TEST_SUITE_P(AllShutterPlugins, ShutterContract, ::testing::ValuesIn(contractCases(PluginKind::Shutter)),
                         contractCaseName);

}  // namespace
}  // namespace rsvio::test
