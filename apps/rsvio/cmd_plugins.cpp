// rsvio plugins [--json]: every plugin found on the search path, with kind, name, version, description
// and its parameter table; libraries that were rejected are listed with the reason.
#include <iomanip>
#include <iostream>
#include <sstream>

#include "commands.h"
#include "rsvio/plugin/host.h"

namespace rsvio::app {

namespace {

std::string rangeOf(const ParamSpec& p) {
  if (p.type == ParamSpec::Type::Enum) {
    std::string s;
    for (const auto& c : p.choices) s += (s.empty() ? "" : "|") + c;
    return s;
  }
  if (p.type != ParamSpec::Type::Int && p.type != ParamSpec::Type::Double && p.type != ParamSpec::Type::DoubleArray)
    return "";
  std::ostringstream ss;
  ss << "[" << (p.min > -1e299 ? std::to_string(p.min) : std::string("-inf")) << ", "
     << (p.max < 1e299 ? std::to_string(p.max) : std::string("inf")) << "]";
  std::string s = ss.str();
  // std::to_string prints 6 decimals; trim trailing zeros for readability.
  std::string out;
  for (size_t i = 0; i < s.size(); ++i) {
    out += s[i];
    if (s[i] == '.') {
      size_t j = i + 1;
      while (j < s.size() && std::isdigit(static_cast<unsigned char>(s[j]))) ++j;
      std::string frac = s.substr(i + 1, j - i - 1);
      while (!frac.empty() && frac.back() == '0') frac.pop_back();
      if (frac.empty()) out.pop_back();
      else out += frac;
      i = j - 1;
    }
  }
  return out;
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

}  // namespace

void addPluginsCommand(CLI::App& root, const GlobalOptions& g, CommandResult& r) {
  auto* sub = root.add_subcommand("plugins", "list every plugin: kind, name, version, description, parameters");
  static bool as_json = false;
  sub->add_flag("--json", as_json, "print JSON instead of a table");
  sub->callback([&g, &r] {
    PluginHost host(PluginHost::defaultSearchPath(g.plugin_path));
    std::vector<std::string> rejected;
    auto infos = host.loadAll(&rejected);
    if (as_json) {
      nlohmann::json j;
      j["search_path"] = host.searchPath();
      j["plugins"] = nlohmann::json::array();
      for (const auto& i : infos) j["plugins"].push_back(toJson(i));
      j["rejected"] = rejected;
      std::cout << j.dump(2) << "\n";
    } else {
      std::string dirs;
      for (const auto& d : host.searchPath()) dirs += (dirs.empty() ? "" : ":") + d;
      std::cout << "plugin search path: " << dirs << "\n";
      for (PluginKind k : allKinds()) {
        std::cout << "\n[" << kindName(k) << "]\n";
        bool any = false;
        for (const auto& i : infos) {
          if (i.kind != k) continue;
          any = true;
          std::cout << "  " << i.name << " " << i.version << ": " << i.description << "\n";
          for (const auto& p : i.params) {
            std::cout << "      " << std::left << std::setw(22) << p.key << std::setw(7) << paramTypeName(p.type)
                      << std::setw(8) << (p.unit.empty() ? "-" : p.unit) << " default " << std::setw(10)
                      << p.default_value.dump() << " " << std::setw(16) << rangeOf(p) << " " << p.description
                      << "\n";
          }
        }
        if (!any) std::cout << "  (none)\n";
      }
      for (const auto& e : rejected) std::cout << "\nrejected: " << e << "\n";
    }
    r.exit_code = rejected.empty() ? 0 : 1;
  });
}

}  // namespace rsvio::app
