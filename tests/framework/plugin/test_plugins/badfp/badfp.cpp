// Test-only: claims to be built by another compiler/Eigen.
#include "rsvio/plugin/plugin_api.h"

extern "C" __attribute__((visibility("default"))) const RsvioPluginEntry* rsvio_plugin_entry() {
  static const RsvioPluginEntry e{RSVIO_PLUGIN_ABI_VERSION, RSVIO_PLUGIN_API_VERSION, "OtherCompiler-1.0/eigen-0.1",
                                  "camera.badfp", [](void*) {}};
  return &e;
}
