#include "render_hook.h"

#include <iostream>

#ifdef RSVIO_HAVE_VIZ
#include "rsvio/viz/render_run.h"
#endif

namespace rsvio::app {

bool renderRunOutputs(const std::string& run_dir, int verbosity) {
#ifdef RSVIO_HAVE_VIZ
  viz::RenderStatus st = viz::renderRunFolder(run_dir);
  if (!st.ok) {
    std::cerr << "rsvio: " << st.message << "\n";
    for (const auto& p : st.problems) std::cerr << "  " << p << "\n";
  } else if (verbosity >= 1) {
    std::cout << "figures: " << st.index_html << "\n";
  }
  return st.ok;
#else
  (void)verbosity;
  std::cerr << "rsvio: figures not rendered for " << run_dir << ": this build has no viz (VTK) library\n";
  return false;
#endif
}

}  // namespace rsvio::app
