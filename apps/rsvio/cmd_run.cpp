// rsvio run: placeholder until its issue lands; says so and exits non-zero.
#include "commands.h"

namespace rsvio::app {
void addRunCommand(CLI::App& root, const GlobalOptions& /*g*/, CommandResult& r) {
  auto* sub = root.add_subcommand("run", "(not available yet)");
  sub->allow_extras();
  sub->callback([&r] { r.exit_code = notAvailableYet("run", "its issue has not landed"); });
}
}  // namespace rsvio::app
