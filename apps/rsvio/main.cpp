// rsvio: the command-line front end. Thin on purpose: each subcommand is in cmd_<name>.cpp.
#include <cstdio>
#include <exception>
#include <iostream>

#include "commands.h"
#include "rsvio/core/error.h"

namespace rsvio::app {
int notAvailableYet(const std::string& command, const std::string& what_is_missing) {
  std::cerr << "rsvio " << command << ": not available yet (" << what_is_missing << ")\n";
  return 3;
}
}  // namespace rsvio::app

int main(int argc, char** argv) {
  using namespace rsvio::app;
  CLI::App root{"rsvio: direct visual-inertial odometry with rolling-shutter cameras"};
  root.require_subcommand(1);
  root.set_version_flag("--version", std::string("rsvio ") + RSVIO_VERSION);
  GlobalOptions g;
  root.add_option("--plugin-path", g.plugin_path,
                  "extra plugin folder, searched before $RSVIO_PLUGIN_PATH and <bin>/plugins")
      ->take_all();
  root.add_flag_callback("-q,--quiet", [&g] { g.verbosity = 0; }, "only errors");
  root.add_flag_callback("-v,--verbose", [&g] { g.verbosity = 2; }, "more progress output");
  CommandResult result;
  addDemoCommand(root, g, result);
  addPluginsCommand(root, g, result);
  addSimulateCommand(root, g, result);
  addRunCommand(root, g, result);
  addEvalCommand(root, g, result);
  addCompareCommand(root, g, result);
  addDiagnoseCommand(root, g, result);
  addRenderCommand(root, g, result);
  try {
    root.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return root.exit(e);
  } catch (const rsvio::Error& e) {
    std::cerr << "rsvio: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "rsvio: unexpected error: " << e.what() << "\n";
    return 2;
  }
  return result.exit_code;
}
