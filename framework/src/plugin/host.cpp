#include "rsvio/plugin/host.h"

#include <dlfcn.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <sstream>

#include "rsvio/config/validate.h"
#include "rsvio/plugin/plugin_api.h"

namespace fs = std::filesystem;

namespace rsvio {

namespace {

constexpr const char* kPrefix = "rsvio_";
constexpr const char* kSuffix = ".so";

// "rsvio_camera_pinhole.so" -> "camera.pinhole" (kind is the part up to the first '_').
std::string nameFromFile(const std::string& file) {
  if (file.rfind(kPrefix, 0) != 0 || file.size() <= 9 || file.substr(file.size() - 3) != kSuffix) return "";
  std::string stem = file.substr(6, file.size() - 9);
  auto us = stem.find('_');
  if (us == std::string::npos || us == 0 || us + 1 == stem.size()) return "";
  return stem.substr(0, us) + "." + stem.substr(us + 1);
}

std::string joinNames(const std::vector<std::string>& names) {
  std::string s;
  for (const auto& n : names) s += (s.empty() ? "" : ", ") + n;
  return s.empty() ? "none" : s;
}

class Registrar : public PluginRegistrar {
 public:
  explicit Registrar(std::string lib) : lib_(std::move(lib)) {}
  void addFactory(PluginInfo info, PluginFactory factory) override {
    info.library_path = lib_;
    added.push_back({std::move(info), std::move(factory)});
  }
  std::string lib_;
  std::vector<std::pair<PluginInfo, PluginFactory>> added;
};

}  // namespace

std::string pluginLibraryFileName(const std::string& name) {
  std::string s = name;
  std::replace(s.begin(), s.end(), '.', '_');
  return kPrefix + s + kSuffix;
}

PluginHost::PluginHost(std::vector<std::string> search_path) : search_path_(std::move(search_path)) {}
PluginHost::~PluginHost() = default;  // libraries stay loaded on purpose (see header)

std::vector<std::string> PluginHost::defaultSearchPath(const std::vector<std::string>& cmdline_dirs) {
  std::vector<std::string> path = cmdline_dirs;
  if (const char* env = std::getenv("RSVIO_PLUGIN_PATH")) {
    std::stringstream ss(env);
    std::string dir;
    while (std::getline(ss, dir, ':'))
      if (!dir.empty()) path.push_back(dir);
  }
  std::error_code ec;
  fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) path.push_back((exe.parent_path() / "plugins").string());
  return path;
}

std::vector<std::string> PluginHost::available() const {
  std::vector<std::string> names;
  for (const auto& dir : search_path_) {
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) continue;
    for (const auto& e : fs::directory_iterator(dir, ec)) {
      std::string n = nameFromFile(e.path().filename().string());
      if (!n.empty() && std::find(names.begin(), names.end(), n) == names.end()) names.push_back(n);
    }
  }
  std::sort(names.begin(), names.end());
  return names;
}

std::vector<std::string> PluginHost::available(PluginKind kind) const {
  std::vector<std::string> out;
  const std::string prefix = std::string(kindName(kind)) + ".";
  for (const auto& n : available())
    if (n.rfind(prefix, 0) == 0) out.push_back(n);
  return out;
}

std::string PluginHost::findLibrary(const std::string& name) const {
  const std::string file = pluginLibraryFileName(name);
  for (const auto& dir : search_path_) {
    fs::path p = fs::path(dir) / file;
    std::error_code ec;
    if (fs::is_regular_file(p, ec)) return p.string();
  }
  return "";
}

void PluginHost::loadLibrary(const std::string& path, const std::string& expected_name) {
  if (loaded_libs_.count(path)) return;
  void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (!handle) {
    const char* err = dlerror();
    throw PluginError(path + ": cannot load plugin library: " + (err ? err : "unknown dlopen error"));
  }
  dlerror();
  using EntryFn = const RsvioPluginEntry* (*)();
  auto entry_fn = reinterpret_cast<EntryFn>(dlsym(handle, "rsvio_plugin_entry"));
  if (!entry_fn) {
    dlclose(handle);  // nothing of it is in use yet
    throw PluginError(path + ": not an rsvio plugin: no rsvio_plugin_entry symbol (build it with rsvio_add_plugin "
                             "and RSVIO_PLUGIN_ENTRY)");
  }
  const RsvioPluginEntry* entry = entry_fn();
  if (!entry) throw PluginError(path + ": rsvio_plugin_entry returned null");
  if (entry->abi_version != RSVIO_PLUGIN_ABI_VERSION)
    throw PluginError(path + ": plugin ABI version " + std::to_string(entry->abi_version) + ", host expects " +
                      std::to_string(RSVIO_PLUGIN_ABI_VERSION) + "; rebuild the plugin against this rsvio");
  if (entry->api_version > RSVIO_PLUGIN_API_VERSION)
    throw PluginError(path + ": plugin needs API version " + std::to_string(entry->api_version) +
                      ", this rsvio provides " + std::to_string(RSVIO_PLUGIN_API_VERSION) + "; update rsvio");
  const std::string fp = entry->fingerprint ? entry->fingerprint : "";
  if (fp != RSVIO_FINGERPRINT)
    throw PluginError(path + ": plugin built as '" + fp + "', host built as '" + RSVIO_FINGERPRINT +
                      "'; rebuild the plugin with the same compiler, Eigen and build type");
  const std::string lib_name = entry->library_name ? entry->library_name : "";
  if (!expected_name.empty() && lib_name != expected_name)
    throw PluginError(path + ": library was built as '" + lib_name + "' but its file name says '" + expected_name +
                      "'");
  Registrar reg(path);
  entry->register_plugins(&reg);
  bool has_own = false;
  for (auto& [info, factory] : reg.added) {
    if (info.name == lib_name) has_own = true;
    auto it = registered_.find(info.name);
    if (it != registered_.end())
      throw PluginError("duplicate plugin name '" + info.name + "': registered by " + it->second.info.library_path +
                        " and by " + path);
    const auto dot = info.name.find('.');
    if (dot == std::string::npos || info.name.substr(0, dot) != kindName(info.kind))
      throw PluginError(path + ": registers '" + info.name + "' as a " + kindName(info.kind) +
                        " plugin; names must be '" + kindName(info.kind) + ".<name>'");
  }
  if (!has_own)
    throw PluginError(path + ": library '" + lib_name + "' does not register a plugin of that name");
  for (auto& [info, factory] : reg.added) registered_[info.name] = Registered{info, std::move(factory)};
  loaded_libs_[path] = lib_name;
}

const PluginInfo& PluginHost::info(const std::string& name) {
  auto it = registered_.find(name);
  if (it != registered_.end()) return it->second.info;
  const auto dot = name.find('.');
  if (dot == std::string::npos || dot == 0 || dot + 1 == name.size())
    throw PluginError("plugin name '" + name + "' is not of the form kind.name (e.g. camera.pinhole)");
  const std::string kind = name.substr(0, dot);
  const auto k = kindFromName(kind);
  if (!k) {
    std::vector<std::string> kinds;
    for (auto kk : allKinds()) kinds.push_back(kindName(kk));
    std::string dym = didYouMean(kind, kinds);
    throw PluginError("unknown plugin kind '" + kind + "' in '" + name + "'" +
                      (dym.empty() ? "" : "; did you mean '" + dym + "'?") + " (kinds: " + joinNames(kinds) + ")");
  }
  const std::string path = findLibrary(name);
  if (path.empty()) {
    auto same_kind = available(*k);
    std::string dym = didYouMean(name, same_kind);
    std::string dirs;
    for (const auto& d : search_path_) dirs += (dirs.empty() ? "" : ":") + d;
    throw PluginError("unknown plugin '" + name + "'" + (dym.empty() ? "" : "; did you mean '" + dym + "'?") +
                      " (available " + kind + " plugins: " + joinNames(same_kind) + "; searched " + dirs + ")");
  }
  loadLibrary(path, name);
  return registered_.at(name).info;
}

std::vector<PluginInfo> PluginHost::loadAll(std::vector<std::string>* rejected) {
  std::vector<PluginInfo> out;
  for (const auto& name : available()) {
    try {
      out.push_back(info(name));
    } catch (const Error& e) {
      if (rejected) rejected->push_back(e.what());
    }
  }
  return out;
}

void PluginHost::checkKind(const std::string& name, PluginKind kind, const std::string& slot) {
  const PluginInfo& i = info(name);
  if (i.kind != kind)
    throw PluginError((slot.empty() ? std::string("") : slot + ": ") + "needs a " + kindName(kind) +
                      " plugin, but '" + name + "' is a " + kindName(i.kind) + " plugin");
}

std::unique_ptr<PluginBase> PluginHost::createBase(const std::string& name, const Params& params) {
  info(name);
  auto& reg = registered_.at(name);
  std::unique_ptr<PluginBase> obj = reg.factory(params);
  if (!obj) throw PluginError(name + ": factory returned no object");
  return obj;
}

}  // namespace rsvio
