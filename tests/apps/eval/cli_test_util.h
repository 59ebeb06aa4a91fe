// Running the rsvio binary from tests: $RSVIO_BIN (set by ctest), output captured to files.
#pragma once
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace rsvio::test {

struct CliResult {
  int exit_code = -1;
  std::string out, err;
};

inline std::string slurp(const std::string& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

inline std::string rsvioBin() {
  const char* b = std::getenv("RSVIO_BIN");
  return b ? b : std::string(RSVIO_BINARY_DIR) + "/bin/rsvio";
}

inline std::string quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

class CliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("rsvio_cli_eval_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
    ASSERT_TRUE(std::filesystem::is_regular_file(rsvioBin())) << "rsvio binary not found: " << rsvioBin();
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  // args: already shell-quoted where needed.
  CliResult run(const std::string& args) const {
    const std::string o = (dir_ / "stdout.txt").string(), e = (dir_ / "stderr.txt").string();
    const int st = std::system((quote(rsvioBin()) + " " + args + " > " + quote(o) + " 2> " + quote(e)).c_str());
    CliResult r;
    r.exit_code = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
    r.out = slurp(o);
    r.err = slurp(e);
    return r;
  }
  std::string write(const std::string& rel, const std::string& text) const {
    const auto p = dir_ / rel;
    std::filesystem::create_directories(p.parent_path());
    std::ofstream(p) << text;
    return p.string();
  }
  std::string path(const std::string& rel) const { return (dir_ / rel).string(); }
  std::filesystem::path dir_;
};

}  // namespace rsvio::test
