// The plugin host: finds plugin libraries by name, checks their ABI, API and build fingerprint, and
// creates plugin objects from validated parameters.
//
// Search path, in order (first match wins):
//   1. folders given on the command line (--plugin-path),
//   2. folders in $RSVIO_PLUGIN_PATH (':'-separated),
//   3. <folder of the running binary>/plugins.
// "kind.name" lives in rsvio_<kind>_<name>.so. A config names plugins, never paths, so a config or a
// dataset cannot make rsvio load arbitrary code from elsewhere.
//
// Libraries stay loaded for the life of the host's process (never dlclose'd): plugin objects may
// outlive the host object, and unloading code with live objects is undefined.
//
// Errors (PluginError, one line): unknown name (with the available names of that kind and a
// did-you-mean), wrong kind for a slot, missing entry symbol, dlopen failure, ABI mismatch,
// fingerprint mismatch, a library registering a name other than its file name, duplicate names.
#pragma once
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "rsvio/core/error.h"
#include "rsvio/plugin/plugin.h"

namespace rsvio {

class PluginHost {
 public:
  // search_path as resolved by defaultSearchPath() or given explicitly (tests).
  explicit PluginHost(std::vector<std::string> search_path);
  ~PluginHost();
  PluginHost(const PluginHost&) = delete;
  PluginHost& operator=(const PluginHost&) = delete;

  // command-line folders, then $RSVIO_PLUGIN_PATH, then <bin>/plugins.
  static std::vector<std::string> defaultSearchPath(const std::vector<std::string>& cmdline_dirs);

  const std::vector<std::string>& searchPath() const { return search_path_; }

  // Names "kind.name" of every plugin library on the search path (by file name; nothing loaded).
  std::vector<std::string> available() const;
  std::vector<std::string> available(PluginKind kind) const;

  // Loads the library holding `name` if needed and returns its info. Throws PluginError.
  const PluginInfo& info(const std::string& name);

  // Loads every library on the search path; libraries that fail are skipped and their reasons
  // returned in `rejected` (for `rsvio plugins`).
  std::vector<PluginInfo> loadAll(std::vector<std::string>* rejected);

  // Checks `name` is of `kind` (slot is the JSON path, for the message). Throws PluginError.
  void checkKind(const std::string& name, PluginKind kind, const std::string& slot);

  // Creates a plugin of interface I from already-validated params (see config/validate.h).
  template <class I>
  std::unique_ptr<I> create(const std::string& name, const Params& params, const std::string& slot = "") {
    checkKind(name, I::kKind, slot);
    std::unique_ptr<PluginBase> base = createBase(name, params);
    return std::unique_ptr<I>(static_cast<I*>(base.release()));
  }

 private:
  std::unique_ptr<PluginBase> createBase(const std::string& name, const Params& params);
  void loadLibrary(const std::string& path, const std::string& expected_name);
  std::string findLibrary(const std::string& name) const;

  struct Registered {
    PluginInfo info;
    PluginFactory factory;
  };
  std::vector<std::string> search_path_;
  std::map<std::string, Registered> registered_;    // by "kind.name"
  std::map<std::string, std::string> loaded_libs_;  // path -> library name
};

// File name of the library holding "kind.name": rsvio_<kind>_<name>.so.
std::string pluginLibraryFileName(const std::string& name);

}  // namespace rsvio
