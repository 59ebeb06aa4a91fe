#include "rsvio/config/config.h"

#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "rsvio/config/validate.h"
#include "rsvio/core/error.h"
#include "rsvio/io/atomic_file.h"

namespace fs = std::filesystem;

namespace rsvio {

namespace {

// Line and column (1-based) of a byte offset, for parse errors.
std::pair<size_t, size_t> lineCol(const std::string& text, size_t byte) {
  size_t line = 1, col = 1;
  for (size_t i = 0; i < byte && i < text.size(); ++i) {
    if (text[i] == '\n') {
      ++line;
      col = 1;
    } else {
      ++col;
    }
  }
  return {line, col};
}

nlohmann::json loadRecursive(const fs::path& path, std::set<std::string>& chain) {
  std::error_code ec;
  const fs::path canon = fs::weakly_canonical(path, ec);
  const std::string key = ec ? path.string() : canon.string();
  if (chain.count(key)) throw ConfigError(path.string() + ": \"extends\" forms a cycle");
  std::ifstream in(path);
  if (!in) throw ConfigError(path.string() + ": cannot open config file");
  std::stringstream ss;
  ss << in.rdbuf();
  nlohmann::json j = parseJsonText(ss.str(), path.string());
  if (!j.is_object()) throw ConfigError(path.string() + ": a config must be a JSON object");
  if (!j.contains("extends")) return j;
  const nlohmann::json ext = j["extends"];
  j.erase("extends");
  std::vector<std::string> bases;
  if (ext.is_string()) {
    bases.push_back(ext.get<std::string>());
  } else if (ext.is_array()) {
    for (const auto& e : ext) {
      if (!e.is_string()) throw ConfigError(path.string() + ": extends: expected a file name or a list of them");
      bases.push_back(e.get<std::string>());
    }
  } else {
    throw ConfigError(path.string() + ": extends: expected a file name or a list of them, found " + ext.dump());
  }
  chain.insert(key);
  nlohmann::json merged = nlohmann::json::object();
  for (const auto& b : bases) {
    fs::path bp = fs::path(b).is_absolute() ? fs::path(b) : path.parent_path() / b;
    if (!fs::exists(bp))
      throw ConfigError(path.string() + ": extends: base config '" + b + "' not found (looked at " + bp.string() +
                        ")");
    merged = mergeConfig(merged, loadRecursive(bp, chain));
  }
  chain.erase(key);
  // Keep nulls of this file until the end, so they can remove keys of the base.
  return mergeConfig(merged, j);
}

void dropNulls(nlohmann::json& j) {
  if (!j.is_object()) return;
  for (auto it = j.begin(); it != j.end();) {
    if (it->is_null()) {
      it = j.erase(it);
    } else {
      dropNulls(*it);
      ++it;
    }
  }
}

}  // namespace

nlohmann::json parseJsonText(const std::string& text, const std::string& origin) {
  try {
    return nlohmann::json::parse(text, nullptr, true, /*ignore_comments=*/true);
  } catch (const nlohmann::json::parse_error& e) {
    auto [line, col] = lineCol(text, e.byte > 0 ? e.byte - 1 : 0);
    std::string what = e.what();
    // nlohmann's message is "[json.exception.parse_error.101] parse error at line 3, column 5: ..."; keep the reason.
    const auto colon = what.rfind(": ");
    std::string reason = colon == std::string::npos ? what : what.substr(colon + 2);
    throw ConfigError(origin + ":" + std::to_string(line) + ":" + std::to_string(col) + ": invalid JSON: " + reason);
  } catch (const nlohmann::json::exception& e) {
    // Not a syntax error but still unreadable, e.g. "number overflow parsing '1e400'" (found by fuzzing).
    std::string what = e.what();
    const auto bracket = what.find("] ");
    throw ConfigError(origin + ": invalid JSON: " + (bracket == std::string::npos ? what : what.substr(bracket + 2)));
  }
}

nlohmann::json mergeConfig(const nlohmann::json& base, const nlohmann::json& overlay) {
  if (!base.is_object() || !overlay.is_object()) return overlay;
  nlohmann::json out = base;
  for (auto it = overlay.begin(); it != overlay.end(); ++it) {
    if (it->is_null()) {
      out.erase(it.key());
    } else if (out.contains(it.key()) && out[it.key()].is_object() && it->is_object()) {
      out[it.key()] = mergeConfig(out[it.key()], *it);
    } else {
      out[it.key()] = *it;
    }
  }
  return out;
}

nlohmann::json loadConfig(const std::string& path) {
  std::set<std::string> chain;
  nlohmann::json j = loadRecursive(path, chain);
  dropNulls(j);
  return j;
}

// True when s is well-formed UTF-8 (a JSON string must be: nlohmann throws on dumping anything else).
static bool isUtf8(const std::string& s) {
  for (size_t i = 0; i < s.size();) {
    const auto c = static_cast<unsigned char>(s[i]);
    const size_t n = c < 0x80 ? 1 : (c >> 5) == 0x6 ? 2 : (c >> 4) == 0xe ? 3 : (c >> 3) == 0x1e ? 4 : 0;
    if (n == 0 || i + n > s.size()) return false;
    for (size_t k = 1; k < n; ++k)
      if ((static_cast<unsigned char>(s[i + k]) >> 6) != 0x2) return false;
    i += n;
  }
  return true;
}

void applySet(nlohmann::json& config, const std::string& assignment) {
  if (!isUtf8(assignment)) throw ConfigError("--set: argument is not valid UTF-8 text");
  const auto eq = assignment.find('=');
  if (eq == std::string::npos)
    throw ConfigError("--set " + assignment + ": expected key=value (e.g. --set frontend.points=800)");
  const std::string path = assignment.substr(0, eq);
  const std::string text = assignment.substr(eq + 1);
  if (path.empty()) throw ConfigError("--set " + assignment + ": empty key");
  nlohmann::json value;
  try {
    value = nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error&) {
    value = text;  // a bare word is a string: --set shutter.plugin=shutter.rolling
  } catch (const nlohmann::json::exception& e) {
    throw ConfigError("--set " + assignment + ": value is not usable JSON (" + e.what() + ")");
  }
  nlohmann::json* node = &config;
  std::stringstream ss(path);
  std::string part;
  std::vector<std::string> parts;
  while (std::getline(ss, part, '.')) {
    if (part.empty()) throw ConfigError("--set " + assignment + ": empty component in key '" + path + "'");
    parts.push_back(part);
  }
  if (value.is_null()) {
    // Removing a key: every component must exist, else the null would silently change nothing (a typo
    // such as effects.rolling_shuter=null). Reported like an unknown key of validation, with a did-you-mean
    // among the keys present at that level.
    const nlohmann::json* at = &config;
    std::string sofar;
    for (const auto& p : parts) {
      const std::string here = sofar.empty() ? p : sofar + "." + p;
      if (!at->is_object() || !at->contains(p)) {
        std::vector<std::string> present;
        if (at->is_object())
          for (auto it = at->begin(); it != at->end(); ++it) present.push_back(it.key());
        const std::string dym = didYouMean(p, present);
        std::string list;
        for (const auto& k : present) list += (list.empty() ? "" : ", ") + k;
        throw ConfigError("--set " + assignment + ": " + here + ": unknown key, nothing to remove" +
                          (dym.empty() ? "" : "; did you mean \"" + (sofar.empty() ? dym : sofar + "." + dym) + "\"?") +
                          " (present" + (sofar.empty() ? "" : " in " + sofar) + ": " + (list.empty() ? "none" : list) + ")");
      }
      at = &at->at(p);
      sofar = here;
    }
  }
  for (size_t i = 0; i + 1 < parts.size(); ++i) {
    nlohmann::json& next = (*node)[parts[i]];
    if (next.is_null()) next = nlohmann::json::object();
    if (!next.is_object())
      throw ConfigError("--set " + assignment + ": '" + parts[i] + "' is not an object (found " + next.dump() + ")");
    node = &next;
  }
  if (value.is_null())
    node->erase(parts.back());
  else
    (*node)[parts.back()] = value;
}

void applySets(nlohmann::json& config, const std::vector<std::string>& assignments) {
  for (const auto& a : assignments) applySet(config, a);
}

nlohmann::json loadConfigWithSets(const std::string& path, const std::vector<std::string>& sets) {
  nlohmann::json j = loadConfig(path);
  applySets(j, sets);
  return j;
}

void writeConfig(const nlohmann::json& config, const std::string& path) {
  const std::string text = config.dump(2) + "\n";
  io::writeFileAtomic(path, [&](std::ostream& out) { out << text; }, "config");
}

}  // namespace rsvio
