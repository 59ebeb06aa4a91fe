// Errors that reach the user. Every error is one line that names what is wrong and where: a file and
// line, a JSON path, a plugin name, a frame and timestamp. The CLI prints what() and exits non-zero;
// nothing in rsvio calls exit() or abort() on bad input.
#pragma once
#include <stdexcept>
#include <string>

namespace rsvio {

// Base of all user-facing errors.
class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& msg) : std::runtime_error(msg) {}
};

// Bad configuration: unknown key, wrong type, out of range, unknown plugin name.
class ConfigError : public Error {
 public:
  using Error::Error;
};

// Bad input data: malformed CSV/YAML/image, NaNs, timestamp problems. Message starts with "file:line:".
class DataError : public Error {
 public:
  using Error::Error;
  // "path:line: message" (line <= 0 leaves the line out).
  static DataError at(const std::string& path, long line, const std::string& msg) {
    return DataError(line > 0 ? path + ":" + std::to_string(line) + ": " + msg : path + ": " + msg);
  }
};

// Plugin host failures: not found, wrong kind, ABI mismatch, duplicate name, missing entry symbol.
class PluginError : public Error {
 public:
  using Error::Error;
};

}  // namespace rsvio
