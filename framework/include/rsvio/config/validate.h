// Validation of a whole config against a schema, before anything is built. Every problem is collected
// and reported at once, each with its JSON path, what was expected, what was found, the allowed set and
// a did-you-mean for unknown keys, in the form
//   camera.params.fx: expected a number in [1, 1e5], found "abc"
//   fronted: unknown key; did you mean "frontend"? (allowed: camera, frontend, ...)
// and defaults are filled in so the result is the effective, fully resolved config.
#pragma once
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "rsvio/plugin/plugin.h"

namespace rsvio {

class PluginHost;

// The schema of a config: a set of top-level entries, each one of
//   - a section: an object validated against a parameter table (e.g. "frontend"),
//   - a single plugin slot of a kind: {"plugin": "kind.name", "params": {...}},
//   - a multi plugin slot: an object of named members, each a plugin slot of that kind,
//   - a single value (e.g. "name", "description").
struct ConfigSchema {
  struct Entry {
    enum class Type { Section, Slot, MultiSlot, Value } type = Type::Value;
    ParamTable table;              // Section
    ParamSpec value;               // Value
    PluginKind kind = PluginKind::Camera;  // Slot / MultiSlot
    std::string default_plugin;    // Slot: used when the slot is absent ("" = slot optional, left out)
    bool required = false;
    std::string description;
  };
  std::string what;                      // "run config", "simulation config"
  std::map<std::string, Entry> entries;  // by top-level key

  ConfigSchema& section(const std::string& key, ParamTable table, std::string description);
  ConfigSchema& slot(const std::string& key, PluginKind kind, std::string default_plugin, std::string description);
  ConfigSchema& multiSlot(const std::string& key, PluginKind kind, std::string description);
  ConfigSchema& value(const std::string& key, ParamSpec spec);
};

struct ConfigProblem {
  std::string path;
  std::string message;
  std::string str() const { return path.empty() ? message : path + ": " + message; }
};

// Validates `config` against `schema`, loading plugins through `host` to read their parameter tables.
// Returns the effective config (defaults filled). Throws ConfigError listing every problem, one per
// line, first line "<origin>: N problem(s)".
// `sets` are the --set assignments applied on top of the file: a problem at (or under, or above) a
// --set key is blamed on that argument ("--set backend.activ_points=100: backend.activ_points: unknown
// key; ...") instead of the file.
nlohmann::json validateConfig(const nlohmann::json& config, const ConfigSchema& schema, PluginHost& host,
                              const std::string& origin, const std::vector<std::string>& sets = {});

// Validates one params object against a table (used for slots and sections); appends problems,
// returns the params with defaults filled.
nlohmann::json validateParams(const nlohmann::json& params, const ParamTable& table, const std::string& path,
                              std::vector<ConfigProblem>& problems);

// The section `section` of an effective config (an empty object when absent) validated against its
// table, defaults filled, as Params; problems (wrong type, unknown key) throw ConfigError listing each
// with its JSON path ("<section>: N problem(s)").
Params sectionParams(const nlohmann::json& effective_config, const std::string& section, const ParamTable& table);

// Did-you-mean: the closest candidate by edit distance, or "" when nothing is close.
std::string didYouMean(const std::string& word, const std::vector<std::string>& candidates);

// The schema of `rsvio run` configs (framework/src/config/run_schema.cpp). Sections added by the
// estimator issues are registered there.
ConfigSchema runConfigSchema();

// Builds a Params for the slot at `path` of an effective (validated) config.
Params slotParams(const nlohmann::json& effective, const std::string& path);

}  // namespace rsvio
