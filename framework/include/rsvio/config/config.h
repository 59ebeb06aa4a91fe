// Configs: JSON files with one shape for every plugin slot (conventions.md, "Configs").
//
//   { "extends": "base.json",                          // path relative to this file; deep-merged
//     "camera":  {"plugin": "camera.pinhole", "params": {...}},          // single-member slot
//     "photometric": {"affine": {"plugin": "photometric.affine"}},      // multi-member: keyed by name
//     "frontend": {"points": 2000} }                                     // framework section
//
// Merging: the file's own keys deep-merge over its base's; an object merges key by key, anything else
// replaces; a null value removes the key. `--set a.b.c=value` applies after the files: value is parsed
// as JSON when it parses (numbers, true/false, null, "quoted", [..], {..}), else taken as a string.
// Validation (config/validate.h) runs on the merged result before anything is built.
#pragma once
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace rsvio {

// Reads a config file, resolving "extends" recursively (cycles are errors). Throws ConfigError with
// "file:line:column: ..." for malformed JSON, naming the file for a missing one.
nlohmann::json loadConfig(const std::string& path);

// Parses JSON text; `origin` names the source in messages.
nlohmann::json parseJsonText(const std::string& text, const std::string& origin);

// Deep merge: overlay's keys over base's; objects merge recursively; null removes.
nlohmann::json mergeConfig(const nlohmann::json& base, const nlohmann::json& overlay);

// Applies one "a.b.c=value" override. Throws ConfigError if the text has no '=' or an empty path.
void applySet(nlohmann::json& config, const std::string& assignment);
void applySets(nlohmann::json& config, const std::vector<std::string>& assignments);

// Loads a file, applies the --set lines, removes nulls left by merging. The usual entry point.
nlohmann::json loadConfigWithSets(const std::string& path, const std::vector<std::string>& sets);

// Writes the effective config as pretty JSON (2-space indent) to path. Throws Error on I/O failure.
void writeConfig(const nlohmann::json& config, const std::string& path);

}  // namespace rsvio
