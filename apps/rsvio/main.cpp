// rsvio: the command-line front end. Thin on purpose: each subcommand is in cmd_<name>.cpp.
// Exit codes (commands.h, README "Exit codes"): 0 ok, 1 a run failed, 2 bad input or usage (CLI11's own
// parse errors included, one line on stderr), 3 not available in this build, 130 interrupted.
#include <cstdio>
#include <exception>
#include <iostream>

#include "commands.h"
#include "rsvio/core/error.h"

namespace rsvio::app {
int notAvailableYet(const std::string& command, const std::string& what_is_missing) {
  std::cerr << "rsvio " << command << ": not available yet (" << what_is_missing << ")\n";
  return kExitNotAvailable;
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
      ->take_all()
      ->check(CLI::ExistingDirectory);
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
    // --help and --version: CLI11 prints them, exit 0. Every other parse error (no subcommand, unknown
    // option, a file that does not exist, a value out of range) is a usage error: one line, exit 2.
    if (e.get_exit_code() == 0) return root.exit(e);
    std::string where = "rsvio";
    for (const CLI::App* sub : root.get_subcommands()) where += " " + sub->get_name();
    std::string what = e.what();
    if (dynamic_cast<const CLI::RequiredError*>(&e) && where == "rsvio" && what.find("ubcommand") != std::string::npos) {
      what = "a subcommand is required:";
      for (const CLI::App* sub : root.get_subcommands([](CLI::App*) { return true; })) what += " " + sub->get_name();
    }
    for (char& c : what)
      if (c == '\n') c = ' ';
    std::cerr << where << ": " << what << " (" << where << " --help for usage)\n";
    return kExitUsage;
  } catch (const rsvio::Error& e) {
    std::cerr << "rsvio: " << e.what() << "\n";
    return kExitUsage;
  } catch (const std::exception& e) {
    std::cerr << "rsvio: unexpected error: " << e.what() << "\n";
    return kExitFailed;
  }
  return result.exit_code;
}
