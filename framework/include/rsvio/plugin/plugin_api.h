// The binary contract between the host and a plugin library.
//
// A plugin library (plugins/<kind>/<name>/, built with rsvio_add_plugin) exports exactly one C symbol,
// `rsvio_plugin_entry`, returning RsvioPluginEntry. The host opens the library with
// dlopen(RTLD_NOW | RTLD_LOCAL), so an unresolved symbol fails at load, and rejects it when:
//   - the ABI version differs (incompatible layout of these structs or of the interfaces),
//   - the build fingerprint differs (compiler, Eigen version, build type: C++ and Eigen objects cross
//     the boundary, so both sides must match),
// and accepts any API version <= its own (API grows compatibly). register_plugins is then called with a
// PluginRegistrar; the library registers its implementations there (no static-initialiser magic).
//
// Usage in a plugin:
//   static void registerAll(rsvio::PluginRegistrar& r) {
//     r.add<rsvio::CameraModel>({"camera.pinhole", rsvio::PluginKind::Camera, "1.0.0", "Pinhole ...", table},
//                               [](const rsvio::Params& p) { return std::make_unique<PinholeCamera>(p); });
//   }
//   RSVIO_PLUGIN_ENTRY(registerAll)
#pragma once
#include <cstdint>
#include <memory>
#include <type_traits>

#include "rsvio/plugin/plugin.h"

#define RSVIO_PLUGIN_ABI_VERSION 5u  // 2: MotionPrior::twistEnergySigma; 3: DiagnosticProbe::evaluate(ProbeInput);
                                     // 4: ShutterModel::estimatesLineDelay; 5: DataSource::imuReader
#define RSVIO_PLUGIN_API_VERSION 1u

extern "C" {
struct RsvioPluginEntry {
  uint32_t abi_version;
  uint32_t api_version;
  const char* fingerprint;              // RSVIO_FINGERPRINT of the plugin's build
  const char* library_name;             // "kind.name" the library was built as
  void (*register_plugins)(void* registrar);  // registrar is a rsvio::PluginRegistrar*
};
}

namespace rsvio {

class PluginRegistrar {
 public:
  virtual ~PluginRegistrar() = default;
  virtual void addFactory(PluginInfo info, PluginFactory factory) = 0;

  // Typed registration: Impl must derive from Interface, and info.kind must be Interface::kKind.
  template <class Interface, class Make>
  void add(PluginInfo info, Make make) {
    info.kind = Interface::kKind;
    addFactory(std::move(info), [make](const Params& p) -> std::unique_ptr<PluginBase> {
      std::unique_ptr<Interface> obj = make(p);
      return std::unique_ptr<PluginBase>(obj.release());
    });
  }
};

}  // namespace rsvio

#ifndef RSVIO_PLUGIN_NAME
#define RSVIO_PLUGIN_NAME "unknown"
#endif

#define RSVIO_PLUGIN_ENTRY(register_fn)                                                       \
  extern "C" __attribute__((visibility("default"))) const RsvioPluginEntry* rsvio_plugin_entry() { \
    static const RsvioPluginEntry entry{                                                      \
        RSVIO_PLUGIN_ABI_VERSION, RSVIO_PLUGIN_API_VERSION, RSVIO_FINGERPRINT, RSVIO_PLUGIN_NAME, \
        [](void* r) { register_fn(*static_cast<rsvio::PluginRegistrar*>(r)); }};             \
    return &entry;                                                                            \
  }
