// The solver contract (tests/support/plugin_contracts.h) run against every solver plugin the host finds.
#include <gtest/gtest.h>

#include "support/plugin_contracts.h"

namespace rsvio::test {
namespace {

class SolverContract : public ::testing::TestWithParam<ContractCase> {
 protected:
  std::unique_ptr<SolverBackend> make() const {
    if (!GetParam().error.empty()) throw Error(GetParam().error);
    return makePlugin<SolverBackend>(GetParam().plugin, GetParam().params);
  }
};

TEST_P(SolverContract, SolvesRandomSpdSystems) { checkSolverSolvesSpd(*make()); }

TEST_P(SolverContract, RefusesIndefiniteAndSingularSystems) { checkSolverRejectsIndefinite(*make()); }

INSTANTIATE_TEST_SUITE_P(AllSolverPlugins, SolverContract, ::testing::ValuesIn(contractCases(PluginKind::Solver)),
                         contractCaseName);

}  // namespace
}  // namespace rsvio::test
