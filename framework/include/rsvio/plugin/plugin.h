// What every plugin is: a kind, a name "kind.name", a version, a description and a parameter table.
// The parameter table drives config validation, `rsvio plugins` and the plugin's README alike.
#pragma once
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace rsvio {

// Every kind of plugin the framework knows. Adding a kind is a framework change; adding a plugin is not.
enum class PluginKind {
  Camera,       // camera.*      projection and distortion (interfaces/camera.h)
  Shutter,      // shutter.*     when each raw row is read: global, rolling (interfaces/shutter.h)
  Motion,       // motion.*      motion priors: constant velocity, IMU, twist priors (interfaces/motion_prior.h)
  Photometric,  // photometric.* affine brightness, vignetting, response (interfaces/photometric.h)
  Solver,       // solver.*      linear solver backends (interfaces/solver.h)
  Source,       // source.*      data sources: dataset readers (interfaces/data_source.h)
  Effect,       // effect.*      simulator effects (interfaces/sim_effect.h)
  Probe,        // probe.*       diagnostic probes, one per physical effect (interfaces/diagnostic_probe.h)
};

const char* kindName(PluginKind kind);
std::optional<PluginKind> kindFromName(const std::string& name);
std::vector<PluginKind> allKinds();

// One parameter of a plugin or a config section. Units go in the key name too (`_us`, `_px`, `_hz`).
struct ParamSpec {
  enum class Type { Bool, Int, Double, String, Enum, DoubleArray };
  std::string key;
  Type type = Type::Double;
  std::string unit;                    // "" for unitless
  nlohmann::json default_value;        // null = required
  double min = -1e300;                 // inclusive range for Int/Double (and DoubleArray elements)
  double max = 1e300;
  std::vector<std::string> choices;    // for Enum
  std::string description;             // one line
  int array_size = -1;                 // DoubleArray: exact size, or -1 for any
};
using ParamTable = std::vector<ParamSpec>;

const char* paramTypeName(ParamSpec::Type t);

// Fluent builders, so tables read like tables.
ParamSpec paramBool(std::string key, bool def, std::string description);
ParamSpec paramInt(std::string key, long def, double min, double max, std::string unit, std::string description);
ParamSpec paramDouble(std::string key, double def, double min, double max, std::string unit,
                      std::string description);
ParamSpec paramString(std::string key, std::string def, std::string description);
ParamSpec paramEnum(std::string key, std::string def, std::vector<std::string> choices, std::string description);
ParamSpec paramArray(std::string key, std::vector<double> def, int size, std::string unit, std::string description);

// Validated parameters with defaults filled in. Getters throw ConfigError if the key is absent or of
// the wrong type (which validation prevents).
class Params {
 public:
  Params() = default;
  explicit Params(nlohmann::json j, std::string where = "") : j_(std::move(j)), where_(std::move(where)) {}
  bool has(const std::string& key) const;
  bool getBool(const std::string& key) const;
  long getInt(const std::string& key) const;
  double getDouble(const std::string& key) const;
  std::string getString(const std::string& key) const;
  std::vector<double> getArray(const std::string& key) const;
  const nlohmann::json& json() const { return j_; }
  const std::string& where() const { return where_; }  // JSON path of the slot, for messages

 private:
  const nlohmann::json& at(const std::string& key) const;
  nlohmann::json j_ = nlohmann::json::object();
  std::string where_;
};

// Base of every plugin object. The destructor is defined in the framework so that typeinfo and vtable
// of the base live in librsvio_framework.so, shared by all plugins.
class PluginBase {
 public:
  virtual ~PluginBase();
};

struct PluginInfo {
  std::string name;          // "kind.name"
  PluginKind kind = PluginKind::Camera;
  std::string version;       // the implementation's own version, e.g. "1.0.0"
  std::string description;   // one line
  ParamTable params;
  std::string library_path;  // filled by the host
};

using PluginFactory = std::function<std::unique_ptr<PluginBase>(const Params&)>;

}  // namespace rsvio
