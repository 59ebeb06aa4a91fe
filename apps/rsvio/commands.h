// The rsvio command-line surface (../shared/guides/user-contract.md). Each subcommand lives in its own
// cmd_<name>.cpp and registers itself on the root CLI11 app through the add*Command function below;
// main.cpp only lists them. A command's callback stores its exit code in `result` and never calls exit():
// errors are thrown as rsvio::Error (one line, naming the file/line/key) and turned into a message on
// stderr plus a non-zero exit code by main.
#pragma once
#include <CLI/CLI.hpp>
#include <string>
#include <vector>

namespace rsvio::app {

// Exit codes, the same for every subcommand (README "Exit codes", user-contract.md).
constexpr int kExitOk = 0;
constexpr int kExitFailed = 1;        // a run (or a run of a grid) failed; its report says why
constexpr int kExitUsage = 2;         // bad input or usage: one line on stderr naming the file, line or key
constexpr int kExitNotAvailable = 3;  // not available in this build
constexpr int kExitInterrupted = 130; // SIGINT/SIGTERM: outputs so far kept, report.json "interrupted"

struct CommandResult {
  int exit_code = 0;
};

// Options shared by every command (plugin search path given on the command line).
struct GlobalOptions {
  std::vector<std::string> plugin_path;  // --plugin-path, searched before $RSVIO_PLUGIN_PATH and <bin>/plugins
  int verbosity = 1;                     // -q 0, default 1, -v 2
};

void addDemoCommand(CLI::App& root, const GlobalOptions& g, CommandResult& r);
void addPluginsCommand(CLI::App& root, const GlobalOptions& g, CommandResult& r);
void addSimulateCommand(CLI::App& root, const GlobalOptions& g, CommandResult& r);
void addRunCommand(CLI::App& root, const GlobalOptions& g, CommandResult& r);
void addEvalCommand(CLI::App& root, const GlobalOptions& g, CommandResult& r);
void addCompareCommand(CLI::App& root, const GlobalOptions& g, CommandResult& r);
void addDiagnoseCommand(CLI::App& root, const GlobalOptions& g, CommandResult& r);
void addRenderCommand(CLI::App& root, const GlobalOptions& g, CommandResult& r);

// A CLI11 check that a path option is not empty (`--out ""`): "--out: empty output folder name".
inline CLI::Validator NonEmpty(const std::string& what) {
  return CLI::Validator([what](std::string& s) { return s.empty() ? "empty " + what + " name" : std::string(); },
                        "NONEMPTY");
}

// For commands whose issue has not landed: a clear message and exit code 3, never a silent success.
int notAvailableYet(const std::string& command, const std::string& what_is_missing);

}  // namespace rsvio::app
