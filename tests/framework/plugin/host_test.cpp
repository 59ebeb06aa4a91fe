// Plugin host: loading a plugin the framework knows nothing of through $RSVIO_PLUGIN_PATH, and every
// failure case with its message (unknown name with did-you-mean, wrong kind, missing entry symbol,
// ABI mismatch, fingerprint mismatch, duplicate name, misnamed library, malformed names).
#include <gtest/gtest.h>
#include <stdlib.h>

#include <filesystem>
#include <fstream>

#include "rsvio/config/validate.h"
#include "rsvio/interfaces/camera.h"
#include "rsvio/interfaces/motion_prior.h"
#include "rsvio/plugin/host.h"
#include "rsvio/plugin/plugin_api.h"

namespace fs = std::filesystem;
using namespace rsvio;

namespace {

// A temporary plugin folder holding copies of the named test plugins.
class TempPluginDir {
 public:
  explicit TempPluginDir(const std::vector<std::string>& names) {
    dir_ = fs::temp_directory_path() / ("rsvio_plugins_" + std::to_string(::getpid()) + "_" + std::to_string(count_++));
    fs::create_directories(dir_);
    for (const auto& n : names) {
      const fs::path src = fs::path(RSVIO_TEST_PLUGIN_DIR) / pluginLibraryFileName(n);
      EXPECT_TRUE(fs::exists(src)) << src;
      fs::copy_file(src, dir_ / src.filename(), fs::copy_options::overwrite_existing);
    }
  }
  ~TempPluginDir() { fs::remove_all(dir_); }
  std::string path() const { return dir_.string(); }

 private:
  fs::path dir_;
  static inline int count_ = 0;
};

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace

TEST(PluginHost, LoadsUnknownToFrameworkPluginThroughEnvironment) {
  TempPluginDir dir({"motion.testonly"});
  ::setenv("RSVIO_PLUGIN_PATH", dir.path().c_str(), 1);
  const auto path = PluginHost::defaultSearchPath({});
  ::unsetenv("RSVIO_PLUGIN_PATH");
  ASSERT_FALSE(path.empty());
  EXPECT_EQ(path.front(), dir.path());  // env before <bin>/plugins
  PluginHost host(path);
  const auto names = host.available(PluginKind::Motion);
  EXPECT_NE(std::find(names.begin(), names.end(), "motion.testonly"), names.end());
  const PluginInfo& info = host.info("motion.testonly");
  EXPECT_EQ(info.kind, PluginKind::Motion);
  EXPECT_EQ(info.version, "0.0.1");
  ASSERT_EQ(info.params.size(), 3u);

  std::vector<ConfigProblem> problems;
  auto params = validateParams(nlohmann::json{{"step_m", 2.0}}, info.params, "motion.x.params", problems);
  ASSERT_TRUE(problems.empty());
  EXPECT_EQ(params["mode"], "fast");  // default filled
  auto prior = host.create<MotionPrior>("motion.testonly", Params(params));
  MotionState s;
  auto guesses = prior->predict({s}, 0);
  ASSERT_EQ(guesses.size(), 1u);
  EXPECT_DOUBLE_EQ(guesses[0].translation().x(), 2.0);
}

TEST(PluginHost, CommandLineFoldersComeFirst) {
  ::setenv("RSVIO_PLUGIN_PATH", "/env/a:/env/b", 1);
  const auto path = PluginHost::defaultSearchPath({"/cmd"});
  ::unsetenv("RSVIO_PLUGIN_PATH");
  ASSERT_GE(path.size(), 4u);
  EXPECT_EQ(path[0], "/cmd");
  EXPECT_EQ(path[1], "/env/a");
  EXPECT_EQ(path[2], "/env/b");
  EXPECT_NE(path[3].find("plugins"), std::string::npos);
}

TEST(PluginHost, UnknownNameListsAvailableAndSuggests) {
  TempPluginDir dir({"motion.testonly"});
  PluginHost host({dir.path()});
  const std::string msg = errorOf([&] { host.info("motion.testonyl"); });
  EXPECT_NE(msg.find("unknown plugin 'motion.testonyl'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("did you mean 'motion.testonly'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("available motion plugins: motion.testonly"), std::string::npos) << msg;
}

TEST(PluginHost, UnknownKindAndMalformedName) {
  PluginHost host({});
  EXPECT_NE(errorOf([&] { host.info("camra.pinhole"); }).find("did you mean 'camera'"), std::string::npos);
  EXPECT_NE(errorOf([&] { host.info("pinhole"); }).find("not of the form kind.name"), std::string::npos);
}

TEST(PluginHost, WrongKindForSlot) {
  TempPluginDir dir({"motion.testonly"});
  PluginHost host({dir.path()});
  const std::string msg = errorOf([&] { host.create<CameraModel>("motion.testonly", Params(), "camera"); });
  EXPECT_NE(msg.find("camera: needs a camera plugin, but 'motion.testonly' is a motion plugin"), std::string::npos)
      << msg;
}

TEST(PluginHost, MissingEntrySymbol) {
  TempPluginDir dir({"camera.noentry"});
  PluginHost host({dir.path()});
  const std::string msg = errorOf([&] { host.info("camera.noentry"); });
  EXPECT_NE(msg.find("no rsvio_plugin_entry symbol"), std::string::npos) << msg;
  EXPECT_NE(msg.find("rsvio_camera_noentry.so"), std::string::npos) << msg;
}

TEST(PluginHost, AbiMismatch) {
  TempPluginDir dir({"camera.badabi"});
  PluginHost host({dir.path()});
  const std::string msg = errorOf([&] { host.info("camera.badabi"); });
  EXPECT_NE(msg.find("plugin ABI version " + std::to_string(RSVIO_PLUGIN_ABI_VERSION + 41) + ", host expects " +
                     std::to_string(RSVIO_PLUGIN_ABI_VERSION)),
            std::string::npos)
      << msg;
}

TEST(PluginHost, FingerprintMismatch) {
  TempPluginDir dir({"camera.badfp"});
  PluginHost host({dir.path()});
  const std::string msg = errorOf([&] { host.info("camera.badfp"); });
  EXPECT_NE(msg.find("OtherCompiler-1.0"), std::string::npos) << msg;
  EXPECT_NE(msg.find("rebuild the plugin"), std::string::npos) << msg;
}

TEST(PluginHost, DuplicateNameIsAnError) {
  TempPluginDir dir({"motion.testonly", "motion.dup"});
  PluginHost host({dir.path()});
  host.info("motion.testonly");
  const std::string msg = errorOf([&] { host.info("motion.dup"); });
  EXPECT_NE(msg.find("duplicate plugin name 'motion.testonly'"), std::string::npos) << msg;
  // The first registration stays intact.
  EXPECT_EQ(host.info("motion.testonly").version, "0.0.1");
}

TEST(PluginHost, LibraryMustRegisterItsOwnName) {
  TempPluginDir dir({"motion.misnamed"});
  PluginHost host({dir.path()});
  const std::string msg = errorOf([&] { host.info("motion.misnamed"); });
  EXPECT_NE(msg.find("does not register a plugin of that name"), std::string::npos) << msg;
}

TEST(PluginHost, NotAnElfFile) {
  TempPluginDir dir({});
  std::ofstream(fs::path(dir.path()) / "rsvio_camera_garbage.so") << "this is not a shared library";
  PluginHost host({dir.path()});
  const std::string msg = errorOf([&] { host.info("camera.garbage"); });
  EXPECT_NE(msg.find("cannot load plugin library"), std::string::npos) << msg;
}

TEST(PluginHost, LoadAllReportsRejectedLibraries) {
  TempPluginDir dir({"motion.testonly", "camera.badabi"});
  PluginHost host({dir.path()});
  std::vector<std::string> rejected;
  auto infos = host.loadAll(&rejected);
  ASSERT_EQ(infos.size(), 1u);
  EXPECT_EQ(infos[0].name, "motion.testonly");
  ASSERT_EQ(rejected.size(), 1u);
  EXPECT_NE(rejected[0].find("ABI"), std::string::npos);
}
