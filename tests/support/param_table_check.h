// "Every table key is read" checks for a subsystem's ParamTable (backend, imu, ...): each key set to a
// value other than its default (inside its range) must reach the options struct. A key that is listed
// (validated, printed by `rsvio plugins`) but never read would silently leave its field at the default.
//
// Use: sec = nonDefaultSection(table); adjust cross-field constraints; read the options from
// {"<section>": sec}; fill `got` with one entry per key from the struct; expectEveryKeyRead(...).
#pragma once
#include <gtest/gtest.h>

#include <algorithm>
#include <nlohmann/json.hpp>
#include <string>

#include "rsvio/plugin/plugin.h"

namespace rsvio {
namespace test {

// Bools flipped, ints one step inside the range, doubles x1.25 (x0.8 at the top of the range; 0 becomes
// half the range's top, at most 0.5).
inline nlohmann::json nonDefaultSection(const ParamTable& table) {
  nlohmann::json sec = nlohmann::json::object();
  for (const ParamSpec& s : table) {
    switch (s.type) {
      case ParamSpec::Type::Bool: sec[s.key] = !s.default_value.get<bool>(); break;
      case ParamSpec::Type::Int: {
        const long d = s.default_value.get<long>();
        sec[s.key] = d + 1 <= s.max ? d + 1 : d - 1;
        break;
      }
      case ParamSpec::Type::Double: {
        const double d = s.default_value.get<double>();
        double v = d == 0.0 ? 0.5 * std::min(1.0, s.max) : d * 1.25;
        if (v > s.max) v = d * 0.8;
        sec[s.key] = v;
        break;
      }
      default: ADD_FAILURE() << s.key << ": unexpected type";
    }
  }
  return sec;
}

// Every key of the table must be in `got` with the value of `sec`, and `got` must hold nothing else.
inline void expectEveryKeyRead(const std::string& section, const ParamTable& table, const nlohmann::json& sec,
                               const nlohmann::json& got) {
  for (const ParamSpec& s : table) {
    ASSERT_TRUE(got.contains(s.key)) << section << "." << s.key << " is in the table but not checked by this test";
    if (s.type == ParamSpec::Type::Double)
      EXPECT_DOUBLE_EQ(got[s.key].get<double>(), sec[s.key].get<double>()) << section << "." << s.key;
    else
      EXPECT_EQ(got[s.key], sec[s.key]) << section << "." << s.key;
  }
  EXPECT_EQ(got.size(), table.size()) << "a field of the " << section << " options checked here is missing from the table";
}

}  // namespace test
}  // namespace rsvio
