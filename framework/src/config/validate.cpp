#include "rsvio/config/validate.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "rsvio/core/error.h"
#include "rsvio/plugin/host.h"

namespace rsvio {

namespace {

// Optimal-string-alignment distance: insertions, deletions, substitutions and adjacent transpositions
// ("nmae" -> "name") each cost 1.
size_t editDistance(const std::string& a, const std::string& b) {
  std::vector<std::vector<size_t>> d(a.size() + 1, std::vector<size_t>(b.size() + 1));
  for (size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  }
  return d[a.size()][b.size()];
}

std::string join(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& e : v) s += (s.empty() ? "" : ", ") + e;
  return s;
}

std::string childPath(const std::string& path, const std::string& key) { return path.empty() ? key : path + "." + key; }

std::string fmtNum(double v) {
  std::ostringstream ss;
  ss << v;
  return ss.str();
}

std::string rangeText(const ParamSpec& s) {
  const bool lo = s.min > -1e299, hi = s.max < 1e299;
  if (lo && hi) return " in [" + fmtNum(s.min) + ", " + fmtNum(s.max) + "]";
  if (lo) return " >= " + fmtNum(s.min);
  if (hi) return " <= " + fmtNum(s.max);
  return "";
}

void unknownKey(const std::string& path, const std::string& key, const std::vector<std::string>& allowed,
                std::vector<ConfigProblem>& problems) {
  const std::string dym = didYouMean(key, allowed);
  problems.push_back({childPath(path, key), "unknown key" + (dym.empty() ? "" : "; did you mean \"" + dym + "\"?") +
                                                " (allowed: " + (allowed.empty() ? "none" : join(allowed)) + ")"});
}

// Checks one value against its spec; appends a problem and returns false when it does not fit.
bool checkValue(const nlohmann::json& v, const ParamSpec& s, const std::string& path,
                std::vector<ConfigProblem>& problems) {
  auto bad = [&](const std::string& expected) {
    problems.push_back({path, "expected " + expected + ", found " + v.dump()});
    return false;
  };
  switch (s.type) {
    case ParamSpec::Type::Bool:
      return v.is_boolean() ? true : bad("true or false");
    case ParamSpec::Type::Int:
      if (!v.is_number_integer()) return bad("an integer" + rangeText(s));
      if (v.get<double>() < s.min || v.get<double>() > s.max) return bad("an integer" + rangeText(s));
      return true;
    case ParamSpec::Type::Double:
      if (!v.is_number() || !std::isfinite(v.get<double>())) return bad("a number" + rangeText(s));
      if (v.get<double>() < s.min || v.get<double>() > s.max) return bad("a number" + rangeText(s));
      return true;
    case ParamSpec::Type::String:
      return v.is_string() ? true : bad("a string");
    case ParamSpec::Type::Enum: {
      if (!v.is_string()) return bad("one of " + join(s.choices));
      const auto str = v.get<std::string>();
      if (std::find(s.choices.begin(), s.choices.end(), str) != s.choices.end()) return true;
      const std::string dym = didYouMean(str, s.choices);
      problems.push_back({path, "expected one of " + join(s.choices) + ", found " + v.dump() +
                                    (dym.empty() ? "" : "; did you mean \"" + dym + "\"?")});
      return false;
    }
    case ParamSpec::Type::DoubleArray: {
      const std::string sz = s.array_size >= 0 ? std::to_string(s.array_size) + " " : "";
      if (!v.is_array() || (s.array_size >= 0 && static_cast<int>(v.size()) != s.array_size))
        return bad("an array of " + sz + "numbers" + rangeText(s));
      for (const auto& e : v)
        if (!e.is_number() || !std::isfinite(e.get<double>()) || e.get<double>() < s.min || e.get<double>() > s.max)
          return bad("an array of " + sz + "numbers" + rangeText(s));
      return true;
    }
  }
  return true;
}

void validateSlot(const nlohmann::json& slot, PluginKind kind, const std::string& path, PluginHost& host,
                  nlohmann::json& out, std::vector<ConfigProblem>& problems) {
  if (!slot.is_object()) {
    problems.push_back({path, std::string("expected {\"plugin\": \"") + kindName(kind) +
                                  ".<name>\", \"params\": {...}}, found " + slot.dump()});
    return;
  }
  for (auto it = slot.begin(); it != slot.end(); ++it)
    if (it.key() != "plugin" && it.key() != "params") unknownKey(path, it.key(), {"params", "plugin"}, problems);
  if (!slot.contains("plugin") || !slot["plugin"].is_string()) {
    problems.push_back({childPath(path, "plugin"), std::string("expected a plugin name \"") + kindName(kind) +
                                                       ".<name>\"" +
                                                       (slot.contains("plugin") ? ", found " + slot["plugin"].dump()
                                                                                : ", found nothing")});
    return;
  }
  const std::string name = slot["plugin"].get<std::string>();
  const PluginInfo* info = nullptr;
  try {
    host.checkKind(name, kind, "");
    info = &host.info(name);
  } catch (const PluginError& e) {
    problems.push_back({childPath(path, "plugin"), e.what()});
    return;
  }
  nlohmann::json params = slot.contains("params") ? slot["params"] : nlohmann::json::object();
  out = nlohmann::json::object();
  out["plugin"] = name;
  out["params"] = validateParams(params, info->params, childPath(path, "params"), problems);
}

}  // namespace

ConfigSchema& ConfigSchema::section(const std::string& key, ParamTable table, std::string description) {
  Entry e;
  e.type = Entry::Type::Section;
  e.table = std::move(table);
  e.description = std::move(description);
  entries[key] = std::move(e);
  return *this;
}

ConfigSchema& ConfigSchema::slot(const std::string& key, PluginKind kind, std::string default_plugin,
                                 std::string description) {
  Entry e;
  e.type = Entry::Type::Slot;
  e.kind = kind;
  e.default_plugin = std::move(default_plugin);
  e.description = std::move(description);
  entries[key] = std::move(e);
  return *this;
}

ConfigSchema& ConfigSchema::multiSlot(const std::string& key, PluginKind kind, std::string description) {
  Entry e;
  e.type = Entry::Type::MultiSlot;
  e.kind = kind;
  e.description = std::move(description);
  entries[key] = std::move(e);
  return *this;
}

ConfigSchema& ConfigSchema::value(const std::string& key, ParamSpec spec) {
  Entry e;
  e.type = Entry::Type::Value;
  e.value = std::move(spec);
  entries[key] = std::move(e);
  return *this;
}

std::string didYouMean(const std::string& word, const std::vector<std::string>& candidates) {
  std::string best;
  size_t best_d = std::string::npos;
  for (const auto& c : candidates) {
    const size_t d = editDistance(word, c);
    if (d < best_d) {
      best_d = d;
      best = c;
    }
  }
  // Close enough: at most a third of the word's letters wrong (at least 1, at most 3).
  const size_t limit = std::clamp<size_t>(word.size() / 3, 1, 3);
  if (best_d <= limit) return best;
  // Or one is a prefix of the other (e.g. "pinhol" -> "camera.pinhole").
  for (const auto& c : candidates)
    if (!word.empty() && (c.find(word) != std::string::npos)) return c;
  return "";
}

nlohmann::json validateParams(const nlohmann::json& params, const ParamTable& table, const std::string& path,
                              std::vector<ConfigProblem>& problems) {
  nlohmann::json out = nlohmann::json::object();
  if (!params.is_object()) {
    problems.push_back({path, "expected an object of parameters, found " + params.dump()});
    return out;
  }
  std::vector<std::string> keys;
  for (const auto& s : table) keys.push_back(s.key);
  for (auto it = params.begin(); it != params.end(); ++it) {
    auto spec = std::find_if(table.begin(), table.end(), [&](const ParamSpec& s) { return s.key == it.key(); });
    if (spec == table.end()) {
      unknownKey(path, it.key(), keys, problems);
      continue;
    }
    if (checkValue(*it, *spec, childPath(path, it.key()), problems)) out[it.key()] = *it;
  }
  for (const auto& s : table) {
    if (out.contains(s.key) || params.contains(s.key)) continue;
    if (s.default_value.is_null()) {
      problems.push_back({childPath(path, s.key), std::string("required ") + paramTypeName(s.type) +
                                                      " parameter is missing (" + s.description + ")"});
    } else {
      out[s.key] = s.default_value;
    }
  }
  return out;
}

namespace {

// The --set assignment whose key is the problem's path, lies under it or above it ("" when none).
std::string blamedSet(const std::string& problem_path, const std::vector<std::string>& sets) {
  auto under = [](const std::string& a, const std::string& b) {  // a == b or a inside b
    return a == b || (a.size() > b.size() && a.compare(0, b.size(), b) == 0 && a[b.size()] == '.');
  };
  for (auto it = sets.rbegin(); it != sets.rend(); ++it) {  // the last --set of a key wins, so blame it
    const std::string key = it->substr(0, it->find('='));
    if (!problem_path.empty() && (under(problem_path, key) || under(key, problem_path))) return *it;
  }
  return "";
}

}  // namespace

nlohmann::json validateConfig(const nlohmann::json& config, const ConfigSchema& schema, PluginHost& host,
                              const std::string& origin, const std::vector<std::string>& sets) {
  std::vector<ConfigProblem> problems;
  nlohmann::json out = nlohmann::json::object();
  if (!config.is_object()) throw ConfigError(origin + ": a config must be a JSON object, found " + config.dump());
  std::vector<std::string> keys;
  for (const auto& [k, e] : schema.entries) keys.push_back(k);
  for (auto it = config.begin(); it != config.end(); ++it)
    if (!schema.entries.count(it.key())) unknownKey("", it.key(), keys, problems);

  for (const auto& [key, e] : schema.entries) {
    const bool present = config.contains(key);
    const nlohmann::json v = present ? config.at(key) : nlohmann::json();
    switch (e.type) {
      case ConfigSchema::Entry::Type::Value:
        if (present) {
          if (checkValue(v, e.value, key, problems)) out[key] = v;
        } else if (!e.value.default_value.is_null()) {
          out[key] = e.value.default_value;
        }
        break;
      case ConfigSchema::Entry::Type::Section:
        out[key] = validateParams(present ? v : nlohmann::json::object(), e.table, key, problems);
        break;
      case ConfigSchema::Entry::Type::Slot:
        if (present) {
          validateSlot(v, e.kind, key, host, out[key], problems);
        } else if (!e.default_plugin.empty()) {
          validateSlot(nlohmann::json{{"plugin", e.default_plugin}}, e.kind, key, host, out[key], problems);
        }
        break;
      case ConfigSchema::Entry::Type::MultiSlot:
        out[key] = nlohmann::json::object();
        if (!present) break;
        if (!v.is_object()) {
          problems.push_back({key, std::string("expected an object of named ") + kindName(e.kind) +
                                       " slots {\"<name>\": {\"plugin\": ...}}, found " + v.dump()});
          break;
        }
        for (auto it = v.begin(); it != v.end(); ++it)
          validateSlot(*it, e.kind, childPath(key, it.key()), host, out[key][it.key()], problems);
        break;
    }
  }
  if (!problems.empty()) {
    // Each problem names where it came from: a --set argument, or the file.
    std::vector<std::string> lines;
    size_t from_sets = 0;
    for (const auto& p : problems) {
      const std::string set = blamedSet(p.path, sets);
      if (!set.empty()) ++from_sets;
      lines.push_back(set.empty() ? p.str() : "--set " + set + ": " + p.str());
    }
    // One problem: one line. Several: a count line, then one line per problem.
    if (problems.size() == 1) throw ConfigError(from_sets ? lines.front() : origin + ": " + lines.front());
    const std::string where = from_sets == problems.size() ? std::string("--set arguments")
                              : from_sets ? origin + " and its --set arguments"
                                          : origin;
    std::string msg = where + ": " + std::to_string(problems.size()) + " problems in the config";
    for (const auto& l : lines) msg += "\n  " + l;
    throw ConfigError(msg);
  }
  return out;
}

Params slotParams(const nlohmann::json& effective, const std::string& path) {
  const nlohmann::json* node = &effective;
  std::stringstream ss(path);
  std::string part;
  while (std::getline(ss, part, '.')) {
    if (!node->is_object() || !node->contains(part)) throw ConfigError(path + ": no such slot in the config");
    node = &node->at(part);
  }
  return Params(node->contains("params") ? node->at("params") : nlohmann::json::object(), path + ".params");
}

Params sectionParams(const nlohmann::json& effective_config, const std::string& section, const ParamTable& table) {
  const nlohmann::json node =
      effective_config.contains(section) ? effective_config.at(section) : nlohmann::json::object();
  std::vector<ConfigProblem> problems;
  const nlohmann::json filled = validateParams(node, table, section, problems);
  if (!problems.empty()) {
    std::string msg = section + ": " + std::to_string(problems.size()) + " problem(s)";
    for (const ConfigProblem& p : problems) msg += "\n" + p.str();
    throw ConfigError(msg);
  }
  return Params(filled, section);
}

}  // namespace rsvio
