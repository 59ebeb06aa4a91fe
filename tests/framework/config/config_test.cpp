// Configs: extends (deep merge, null removes, cycles), --set, JSON parse errors with line and column,
// and validation reporting every problem at once with JSON path, expectation, finding and did-you-mean.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "rsvio/config/config.h"
#include "rsvio/config/validate.h"
#include "rsvio/core/error.h"
#include "rsvio/plugin/host.h"

namespace fs = std::filesystem;
using namespace rsvio;
using json = nlohmann::json;

namespace {

class TempDir {
 public:
  TempDir() {
    dir_ = fs::temp_directory_path() / ("rsvio_cfg_" + std::to_string(::getpid()) + "_" + std::to_string(n_++));
    fs::create_directories(dir_);
  }
  ~TempDir() { fs::remove_all(dir_); }
  std::string write(const std::string& name, const std::string& text) const {
    std::ofstream(dir_ / name) << text;
    return (dir_ / name).string();
  }

 private:
  fs::path dir_;
  static inline int n_ = 0;
};

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

// A schema using the test-only plugin (built in tests/framework/plugin/test_plugins/good).
ConfigSchema testSchema() {
  ConfigSchema s;
  s.what = "test config";
  s.value("name", paramString("name", "", "name"));
  s.section("frontend", {paramInt("points", 2000, 100, 10000, "", "active points"),
                         paramDouble("huber_px", 9.0, 0.1, 100.0, "", "huber threshold"),
                         paramEnum("mode", "fast", {"fast", "accurate"}, "mode")},
            "front end");
  s.multiSlot("motion", PluginKind::Motion, "motion priors");
  s.slot("prior", PluginKind::Motion, "", "one prior");
  return s;
}

}  // namespace

TEST(Config, ExtendsDeepMergesAndNullRemoves) {
  TempDir d;
  d.write("base.json", R"({"frontend": {"points": 2000, "huber_px": 9}, "motion": {"a": {"plugin": "motion.x"},
                           "b": {"plugin": "motion.y"}}, "name": "base"})");
  const auto child = d.write("child.json", R"({"extends": "base.json", "frontend": {"points": 800},
                                               "motion": {"b": null}, "name": "child"})");
  json j = loadConfig(child);
  EXPECT_EQ(j["frontend"]["points"], 800);
  EXPECT_EQ(j["frontend"]["huber_px"], 9);  // kept from the base
  EXPECT_TRUE(j["motion"].contains("a"));
  EXPECT_FALSE(j["motion"].contains("b"));  // null removed it
  EXPECT_EQ(j["name"], "child");
  EXPECT_FALSE(j.contains("extends"));
}

TEST(Config, ExtendsCycleAndMissingBase) {
  TempDir d;
  d.write("a.json", R"({"extends": "b.json"})");
  const auto b = d.write("b.json", R"({"extends": "a.json"})");
  EXPECT_NE(errorOf([&] { loadConfig(b); }).find("cycle"), std::string::npos);
  const auto c = d.write("c.json", R"({"extends": "nothere.json"})");
  const auto msg = errorOf([&] { loadConfig(c); });
  EXPECT_NE(msg.find("base config 'nothere.json' not found"), std::string::npos) << msg;
}

TEST(Config, ParseErrorNamesFileLineAndColumn) {
  TempDir d;
  const auto p = d.write("bad.json", "{\n  \"a\": 1,\n  \"b\": ,\n}\n");
  const auto msg = errorOf([&] { loadConfig(p); });
  EXPECT_NE(msg.find("bad.json:3:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("invalid JSON"), std::string::npos) << msg;
  EXPECT_NE(errorOf([&] { loadConfig(d.write("x", "")); }).find("invalid JSON"), std::string::npos);
  EXPECT_NE(errorOf([&] { loadConfig("/nonexistent/rsvio.json"); }).find("/nonexistent/rsvio.json: cannot open"),
            std::string::npos);
}

TEST(Config, SetOverridesParseJsonOrString) {
  json j = {{"frontend", {{"points", 2000}}}};
  applySets(j, {"frontend.points=800", "shutter.plugin=shutter.rolling", "frontend.flag=true",
                "frontend.list=[1,2]", "frontend.points_str=\"800\""});
  EXPECT_EQ(j["frontend"]["points"], 800);
  EXPECT_EQ(j["shutter"]["plugin"], "shutter.rolling");
  EXPECT_EQ(j["frontend"]["flag"], true);
  EXPECT_EQ(j["frontend"]["list"], json::array({1, 2}));
  EXPECT_EQ(j["frontend"]["points_str"], "800");
  applySet(j, "frontend.flag=null");
  EXPECT_FALSE(j["frontend"].contains("flag"));
  EXPECT_NE(errorOf([&] { applySet(j, "frontend.points"); }).find("expected key=value"), std::string::npos);
  EXPECT_NE(errorOf([&] { applySet(j, "frontend.points.x=1"); }).find("'points' is not an object"),
            std::string::npos);
  EXPECT_NE(errorOf([&] { applySet(j, "a..b=1"); }).find("empty component"), std::string::npos);
}

TEST(Config, ValidationReportsEveryProblemAtOnce) {
  PluginHost host({RSVIO_TEST_PLUGIN_DIR});
  json cfg = json::parse(R"({
    "nmae": "x",
    "frontend": {"points": 50, "huber_px": "big", "mode": "fats", "pionts": 3},
    "motion": {"cv": {"plugin": "motion.testonly", "params": {"step_m": 20, "cuont": 2}},
               "bad": {"plugin": "motion.nothere"}},
    "prior": {"plugin": "camera.badabi"}
  })");
  const auto msg = errorOf([&] { validateConfig(cfg, testSchema(), host, "cfg.json"); });
  EXPECT_NE(msg.find("cfg.json: 9 problems in the config"), std::string::npos) << msg;
  EXPECT_NE(msg.find("nmae: unknown key; did you mean \"name\"?"), std::string::npos) << msg;
  EXPECT_NE(msg.find("frontend.points: expected an integer in [100, 10000], found 50"), std::string::npos) << msg;
  EXPECT_NE(msg.find("frontend.huber_px: expected a number in [0.1, 100], found \"big\""), std::string::npos) << msg;
  EXPECT_NE(msg.find("frontend.mode: expected one of fast, accurate, found \"fats\"; did you mean \"fast\"?"),
            std::string::npos)
      << msg;
  EXPECT_NE(msg.find("frontend.pionts: unknown key; did you mean \"points\"?"), std::string::npos) << msg;
  EXPECT_NE(msg.find("motion.cv.params.step_m: expected a number in [0, 10], found 20"), std::string::npos) << msg;
  EXPECT_NE(msg.find("motion.cv.params.cuont: unknown key; did you mean \"count\"?"), std::string::npos) << msg;
  EXPECT_NE(msg.find("motion.bad.plugin: unknown plugin 'motion.nothere'"), std::string::npos) << msg;
  // The wrong-kind slot also fails (badabi is rejected at load; the message names the slot path).
  EXPECT_NE(msg.find("prior.plugin:"), std::string::npos) << msg;
}

TEST(Config, ValidationFillsDefaultsAndWrongKindIsNamed) {
  PluginHost host({RSVIO_TEST_PLUGIN_DIR});
  json ok = validateConfig(json::parse(R"({"motion": {"cv": {"plugin": "motion.testonly"}}})"), testSchema(), host,
                           "cfg.json");
  EXPECT_EQ(ok["frontend"]["points"], 2000);
  EXPECT_EQ(ok["motion"]["cv"]["params"]["step_m"], 0.5);
  EXPECT_EQ(ok["name"], "");
  Params p = slotParams(ok, "motion.cv");
  EXPECT_DOUBLE_EQ(p.getDouble("step_m"), 0.5);

  ConfigSchema s;
  s.slot("camera", PluginKind::Camera, "", "camera");
  const auto msg = errorOf(
      [&] { validateConfig(json::parse(R"({"camera": {"plugin": "motion.testonly"}})"), s, host, "c.json"); });
  EXPECT_NE(msg.find("c.json: camera.plugin: needs a camera plugin, but 'motion.testonly' is a motion plugin"),
            std::string::npos)
      << msg;
  const auto msg2 = errorOf([&] {
    validateConfig(json::parse(R"({"camera": {"plugin": "camera.x", "parms": {}}})"), s, host, "c.json");
  });
  EXPECT_NE(msg2.find("camera.parms: unknown key; did you mean \"params\"?"), std::string::npos) << msg2;
}

TEST(Config, DidYouMean) {
  EXPECT_EQ(didYouMean("fronted", {"frontend", "backend", "output"}), "frontend");
  EXPECT_EQ(didYouMean("zzzzzz", {"frontend", "backend"}), "");
}

// A null on a key that does not exist would silently change nothing (a typo): an error with a
// did-you-mean among the keys present at that level, also for a missing parent.
TEST(Config, SetNullOnAMissingKeyIsAnError) {
  json j = {{"effects", {{"rolling_shutter", {{"plugin", "effect.rolling_shutter"}}}, {"image_noise", json::object()}}}};
  const std::string msg = errorOf([&] { applySet(j, "effects.rolling_shuter=null"); });
  EXPECT_NE(msg.find("--set effects.rolling_shuter=null: effects.rolling_shuter: unknown key, nothing to remove; "
                     "did you mean \"effects.rolling_shutter\"?"),
            std::string::npos)
      << msg;
  EXPECT_TRUE(j["effects"].contains("rolling_shutter"));
  EXPECT_NE(errorOf([&] { applySet(j, "efects.rolling_shutter=null"); }).find("did you mean \"effects\"?"),
            std::string::npos);
  EXPECT_FALSE(j.contains("efects")) << "a failed removal creates nothing";
  applySet(j, "effects.rolling_shutter=null");
  EXPECT_FALSE(j["effects"].contains("rolling_shutter"));
}

// Problems at a --set key (or under or above it) blame that argument; the file's own problems name it.
TEST(Config, ValidationBlamesTheSetArgument) {
  PluginHost host({RSVIO_TEST_PLUGIN_DIR});
  const json cfg = json::parse(R"({"frontend": {"pionts": 3}, "nmae": "x"})");
  const auto one = errorOf([&] {
    validateConfig(json::parse(R"({"frontend": {"pionts": 3}})"), testSchema(), host, "cfg.json", {"frontend.pionts=3"});
  });
  EXPECT_EQ(one.rfind("--set frontend.pionts=3: frontend.pionts: unknown key; did you mean \"points\"?", 0), 0u) << one;
  EXPECT_EQ(one.find("cfg.json"), std::string::npos) << one;
  const auto two = errorOf([&] { validateConfig(cfg, testSchema(), host, "cfg.json", {"frontend.pionts=3"}); });
  EXPECT_NE(two.find("cfg.json and its --set arguments: 2 problems"), std::string::npos) << two;
  EXPECT_NE(two.find("\n  --set frontend.pionts=3: frontend.pionts: unknown key"), std::string::npos) << two;
  EXPECT_NE(two.find("\n  nmae: unknown key"), std::string::npos) << two;
  // A set of a whole section is blamed for the problems inside it.
  const auto sec = errorOf([&] { validateConfig(cfg, testSchema(), host, "cfg.json", {"frontend={\"pionts\": 3}"}); });
  EXPECT_NE(sec.find("--set frontend={\"pionts\": 3}: frontend.pionts"), std::string::npos) << sec;
}
