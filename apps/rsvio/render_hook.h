// Rendering at the end of run/compare/demo. viz/ is optional at build time (RSVIO_HAVE_VIZ); a failed
// render never breaks a run: it is reported on stderr and the run's other outputs stay.
#pragma once
#include <string>

namespace rsvio::app {
// Renders <run_dir>/figures and <run_dir>/index.html. Returns false (after printing why) on failure.
bool renderRunOutputs(const std::string& run_dir, int verbosity);
}  // namespace rsvio::app
