// rsvio plugins [--json]: every plugin found on the search path, with kind, name, version, description
// and its parameter table; libraries that were rejected are listed with the reason (exit 2). Then the
// keys of the framework's own config sections (frontend, backend, output of a run config; scene, motion,
// ... of a simulation config) from the same ParamTables that validate them (config/run_schema.cpp).
#include <algorithm>
#include <cmath>
#include <array>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "commands.h"
#include "rsvio/config/validate.h"
#include "rsvio/plugin/host.h"
#include "rsvio/sim/sim_config.h"

namespace rsvio::app {

namespace {

// Short numbers: 0.0001, 44.8, 1e+12 (6 significant digits), as a user would type them.
std::string shortNum(double v) {
  std::ostringstream ss;
  if (std::abs(v) < 1e15 && v == std::floor(v)) ss << static_cast<long long>(v);  // 2147483647, not 2.14748e+09
  else ss << v;
  std::string t = ss.str();
  // Whole numbers of 10 digits or more read better as powers of ten: 1000000000000 -> 1e+12.
  if (t.size() >= 10 && t.find_first_not_of("0", 1) == std::string::npos && (t[0] == '1')) t = "1e+" + std::to_string(t.size() - 1);
  return t;
}

std::string rangeOf(const ParamSpec& p) {
  if (p.type == ParamSpec::Type::Enum) {
    std::string s;
    for (const auto& c : p.choices) s += (s.empty() ? "" : "|") + c;
    return s;
  }
  if (p.type != ParamSpec::Type::Int && p.type != ParamSpec::Type::Double && p.type != ParamSpec::Type::DoubleArray)
    return "";
  return "[" + (p.min > -1e299 ? shortNum(p.min) : std::string("-inf")) + ", " +
         (p.max < 1e299 ? shortNum(p.max) : std::string("inf")) + "]";
}

// A default as JSON, with doubles shortened (44.800000000000004 -> 44.8).
std::string defaultText(const nlohmann::json& v) {
  if (v.is_null()) return "(required)";
  if (v.is_number_float()) return shortNum(v.get<double>());
  if (v.is_array()) {
    std::string s;
    for (const auto& e : v) s += (s.empty() ? "" : ",") + defaultText(e);
    return "[" + s + "]";
  }
  return v.dump();
}

nlohmann::json toJson(const PluginInfo& i) {
  nlohmann::json j;
  j["name"] = i.name;
  j["kind"] = kindName(i.kind);
  j["version"] = i.version;
  j["description"] = i.description;
  j["library"] = i.library_path;
  j["params"] = nlohmann::json::array();
  for (const auto& p : i.params) {
    nlohmann::json q;
    q["key"] = p.key;
    q["type"] = paramTypeName(p.type);
    q["unit"] = p.unit;
    q["default"] = p.default_value;
    if (p.min > -1e299) q["min"] = p.min;
    if (p.max < 1e299) q["max"] = p.max;
    if (!p.choices.empty()) q["choices"] = p.choices;
    if (p.array_size >= 0) q["size"] = p.array_size;
    q["description"] = p.description;
    j["params"].push_back(q);
  }
  return j;
}

// One aligned table of parameters: columns sized to their longest cell (long units, long defaults and
// long ranges do not push the description out of line).
void printParamTable(const ParamTable& params, const std::string& indent, const std::string& prefix = "") {
  std::vector<std::array<std::string, 6>> rows;
  for (const auto& p : params) {
    rows.push_back({prefix + p.key, paramTypeName(p.type), p.unit.empty() ? "-" : p.unit,
                    defaultText(p.default_value), rangeOf(p), p.description});
  }
  std::array<size_t, 6> w{};
  for (const auto& r : rows)
    for (size_t c = 0; c < 5; ++c) w[c] = std::max(w[c], r[c].size());
  for (const auto& r : rows) {
    std::string line = indent;
    for (size_t c = 0; c < 5; ++c) {
      if (w[c] == 0) continue;
      line += r[c] + std::string(w[c] - r[c].size() + 2, ' ');
    }
    line += r[5];
    std::cout << line << "\n";
  }
}

nlohmann::json tableJson(const ParamTable& params) {
  PluginInfo i;
  i.params = params;
  return toJson(i)["params"];
}

// The framework's own config sections (frontend, backend, output, ...) and top-level values of a schema.
nlohmann::json schemaJson(const ConfigSchema& schema) {
  nlohmann::json j = nlohmann::json::object();
  for (const auto& [key, e] : schema.entries) {
    if (e.type == ConfigSchema::Entry::Type::Section) {
      j[key] = {{"description", e.description}, {"params", tableJson(e.table)}};
    } else if (e.type == ConfigSchema::Entry::Type::Value) {
      j[key] = {{"description", e.value.description}, {"params", tableJson({e.value})}};
    } else {
      j[key] = {{"description", e.description}, {"kind", kindName(e.kind)},
                {"multi", e.type == ConfigSchema::Entry::Type::MultiSlot}, {"default", e.default_plugin}};
    }
  }
  return j;
}

void printSchema(const ConfigSchema& schema, const std::string& example) {
  std::cout << "\n[" << schema.what << " keys] (" << example << ")\n";
  ParamTable values;
  for (const auto& [key, e] : schema.entries)
    if (e.type == ConfigSchema::Entry::Type::Value) values.push_back(e.value);
  if (!values.empty()) {
    std::cout << "  top level\n";
    printParamTable(values, "      ");
  }
  std::vector<std::array<std::string, 4>> slots;
  for (const auto& [key, e] : schema.entries) {
    if (e.type != ConfigSchema::Entry::Type::Slot && e.type != ConfigSchema::Entry::Type::MultiSlot) continue;
    const bool multi = e.type == ConfigSchema::Entry::Type::MultiSlot;
    slots.push_back({key,
                     multi ? std::string("{\"<name>\": {\"plugin\": \"") + kindName(e.kind) + ".*\"}}"
                           : std::string("{\"plugin\": \"") + kindName(e.kind) + ".*\"}",
                     e.default_plugin.empty() ? (multi ? "none by default" : "optional") : "default " + e.default_plugin,
                     e.description});
  }
  if (!slots.empty()) {
    std::cout << "  plugin slots (their params: the plugin's table above)\n";
    std::array<size_t, 3> w{};
    for (const auto& r : slots)
      for (size_t c = 0; c < 3; ++c) w[c] = std::max(w[c], r[c].size());
    for (const auto& r : slots) {
      std::string line = "      ";
      for (size_t c = 0; c < 3; ++c) line += r[c] + std::string(w[c] - r[c].size() + 2, ' ');
      std::cout << line << r[3] << "\n";
    }
  }
  for (const auto& [key, e] : schema.entries) {
    if (e.type != ConfigSchema::Entry::Type::Section) continue;
    std::cout << "  " << key << ": " << e.description << "\n";
    printParamTable(e.table, "      ", key + ".");
  }
}

}  // namespace

void addPluginsCommand(CLI::App& root, const GlobalOptions& g, CommandResult& r) {
  auto* sub = root.add_subcommand("plugins",
                                  "list every plugin (kind, name, version, description, parameters) and the keys of "
                                  "run and simulation configs");
  static bool as_json = false;
  sub->add_flag("--json", as_json, "print JSON instead of a table");
  sub->callback([&g, &r] {
    PluginHost host(PluginHost::defaultSearchPath(g.plugin_path));
    std::vector<std::string> rejected;
    auto infos = host.loadAll(&rejected);
    const ConfigSchema run_schema = runConfigSchema();
    const ConfigSchema sim_schema = sim::simConfigSchema();
    if (as_json) {
      nlohmann::json j;
      j["search_path"] = host.searchPath();
      j["plugins"] = nlohmann::json::array();
      for (const auto& i : infos) j["plugins"].push_back(toJson(i));
      j["rejected"] = rejected;
      j["run_config"] = schemaJson(run_schema);
      j["sim_config"] = schemaJson(sim_schema);
      std::cout << j.dump(2) << "\n";
    } else {
      std::string dirs;
      for (const auto& d : host.searchPath()) dirs += (dirs.empty() ? "" : ":") + d;
      std::cout << "plugin search path: " << dirs << "\n";
      for (PluginKind k : allKinds()) {
        std::vector<const PluginInfo*> of_kind;
        for (const auto& i : infos)
          if (i.kind == k) of_kind.push_back(&i);
        if (of_kind.empty()) {
          std::cout << "\n[" << kindName(k) << "] none yet\n";
          continue;
        }
        std::cout << "\n[" << kindName(k) << "]\n";
        for (const PluginInfo* i : of_kind) {
          std::cout << "  " << i->name << " " << i->version << ": " << i->description << "\n";
          printParamTable(i->params, "      ");
        }
      }
      printSchema(run_schema, "rsvio run --config; e.g. --set frontend.points=800");
      printSchema(sim_schema, "rsvio simulate --config; e.g. --set motion.duration_s=10");
      for (const auto& e : rejected) std::cout << "\nrejected: " << e << "\n";
    }
    // A library on the search path that cannot be loaded is bad input (exit 2), said once on stderr too.
    if (!rejected.empty())
      std::cerr << "rsvio plugins: " << rejected.size() << " plugin librar" << (rejected.size() == 1 ? "y" : "ies")
                << " rejected (listed " << (as_json ? "in \"rejected\"" : "at the end") << ")\n";
    r.exit_code = rejected.empty() ? kExitOk : kExitUsage;
  });
}

}  // namespace rsvio::app
