#include "rsvio/plugin/plugin.h"

#include <sstream>

#include "rsvio/core/error.h"

namespace rsvio {

PluginBase::~PluginBase() = default;

namespace {
struct KindRow {
  PluginKind kind;
  const char* name;
};
constexpr KindRow kKinds[] = {
    {PluginKind::Camera, "camera"}, {PluginKind::Shutter, "shutter"},         {PluginKind::Motion, "motion"},
    {PluginKind::Photometric, "photometric"}, {PluginKind::Solver, "solver"}, {PluginKind::Source, "source"},
    {PluginKind::Effect, "effect"}, {PluginKind::Probe, "probe"},
};
}  // namespace

const char* kindName(PluginKind kind) {
  for (const auto& k : kKinds)
    if (k.kind == kind) return k.name;
  return "unknown";
}

std::optional<PluginKind> kindFromName(const std::string& name) {
  for (const auto& k : kKinds)
    if (name == k.name) return k.kind;
  return std::nullopt;
}

std::vector<PluginKind> allKinds() {
  std::vector<PluginKind> v;
  for (const auto& k : kKinds) v.push_back(k.kind);
  return v;
}

const char* paramTypeName(ParamSpec::Type t) {
  switch (t) {
    case ParamSpec::Type::Bool: return "bool";
    case ParamSpec::Type::Int: return "int";
    case ParamSpec::Type::Double: return "number";
    case ParamSpec::Type::String: return "string";
    case ParamSpec::Type::Enum: return "enum";
    case ParamSpec::Type::DoubleArray: return "array";
  }
  return "?";
}

ParamSpec paramBool(std::string key, bool def, std::string description) {
  ParamSpec p;
  p.key = std::move(key);
  p.type = ParamSpec::Type::Bool;
  p.default_value = def;
  p.description = std::move(description);
  return p;
}

ParamSpec paramInt(std::string key, long def, double min, double max, std::string unit, std::string description) {
  ParamSpec p;
  p.key = std::move(key);
  p.type = ParamSpec::Type::Int;
  p.default_value = def;
  p.min = min;
  p.max = max;
  p.unit = std::move(unit);
  p.description = std::move(description);
  return p;
}

ParamSpec paramDouble(std::string key, double def, double min, double max, std::string unit,
                      std::string description) {
  ParamSpec p = paramInt(std::move(key), 0, min, max, std::move(unit), std::move(description));
  p.type = ParamSpec::Type::Double;
  p.default_value = def;
  return p;
}

ParamSpec paramString(std::string key, std::string def, std::string description) {
  ParamSpec p;
  p.key = std::move(key);
  p.type = ParamSpec::Type::String;
  p.default_value = std::move(def);
  p.description = std::move(description);
  return p;
}

ParamSpec paramEnum(std::string key, std::string def, std::vector<std::string> choices, std::string description) {
  ParamSpec p = paramString(std::move(key), std::move(def), std::move(description));
  p.type = ParamSpec::Type::Enum;
  p.choices = std::move(choices);
  return p;
}

ParamSpec paramArray(std::string key, std::vector<double> def, int size, std::string unit, std::string description) {
  ParamSpec p;
  p.key = std::move(key);
  p.type = ParamSpec::Type::DoubleArray;
  p.default_value = def;
  p.array_size = size;
  p.unit = std::move(unit);
  p.description = std::move(description);
  return p;
}

const nlohmann::json& Params::at(const std::string& key) const {
  if (!j_.is_object() || !j_.contains(key))
    throw ConfigError((where_.empty() ? std::string("params") : where_) + "." + key + ": missing parameter");
  return j_.at(key);
}

bool Params::has(const std::string& key) const { return j_.is_object() && j_.contains(key) && !j_.at(key).is_null(); }

namespace {
[[noreturn]] void wrongType(const std::string& where, const std::string& key, const char* expected,
                            const nlohmann::json& found) {
  throw ConfigError((where.empty() ? std::string("params") : where) + "." + key + ": expected " + expected +
                    ", found " + found.dump());
}
}  // namespace

bool Params::getBool(const std::string& key) const {
  const auto& v = at(key);
  if (!v.is_boolean()) wrongType(where_, key, "a bool", v);
  return v.get<bool>();
}

long Params::getInt(const std::string& key) const {
  const auto& v = at(key);
  if (!v.is_number_integer()) wrongType(where_, key, "an integer", v);
  return v.get<long>();
}

double Params::getDouble(const std::string& key) const {
  const auto& v = at(key);
  if (!v.is_number()) wrongType(where_, key, "a number", v);
  return v.get<double>();
}

std::string Params::getString(const std::string& key) const {
  const auto& v = at(key);
  if (!v.is_string()) wrongType(where_, key, "a string", v);
  return v.get<std::string>();
}

std::vector<double> Params::getArray(const std::string& key) const {
  const auto& v = at(key);
  if (!v.is_array()) wrongType(where_, key, "an array of numbers", v);
  std::vector<double> out;
  for (const auto& e : v) {
    if (!e.is_number()) wrongType(where_, key, "an array of numbers", v);
    out.push_back(e.get<double>());
  }
  return out;
}

}  // namespace rsvio
