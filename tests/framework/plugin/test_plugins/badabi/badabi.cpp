// Test-only: reports an ABI version the host does not speak.
#include "rsvio/plugin/plugin_api.h"

extern "C" __attribute__((visibility("default"))) const RsvioPluginEntry* rsvio_plugin_entry() {
  static const RsvioPluginEntry e{RSVIO_PLUGIN_ABI_VERSION + 41, RSVIO_PLUGIN_API_VERSION, RSVIO_FINGERPRINT,
                                  "camera.badabi", [](void*) {}};
  return &e;
}
