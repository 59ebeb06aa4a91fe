// DisplayGuard: with DISPLAY unset it starts an Xvfb, publishes it in DISPLAY, and stops it again.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>

#include <cstdlib>

#include "rsvio/viz/display_guard.h"

namespace rsvio::viz {
namespace {

TEST(DisplayGuard, StartsXvfbWhenDisplayIsUnsetAndCleansUp) {
  ::unsetenv("DISPLAY");
  pid_t pid = -1;
  std::string display;
  {
    DisplayGuard guard;
    ASSERT_TRUE(guard.ok()) << guard.message();
    ASSERT_TRUE(guard.startedXvfb());
    pid = guard.xvfbPid();
    display = guard.display();
    ASSERT_NE(std::getenv("DISPLAY"), nullptr);
    EXPECT_EQ(std::string(std::getenv("DISPLAY")), display);
    EXPECT_TRUE(canOpenDisplay(display));
    struct stat st {};
    EXPECT_EQ(::stat(("/tmp/.X11-unix/X" + display.substr(1)).c_str(), &st), 0);
    // A nested guard finds the display and starts nothing.
    DisplayGuard inner;
    EXPECT_TRUE(inner.ok());
    EXPECT_FALSE(inner.startedXvfb());
  }
  EXPECT_EQ(std::getenv("DISPLAY"), nullptr) << "DISPLAY must be restored (unset)";
  EXPECT_NE(::kill(pid, 0), 0) << "Xvfb " << pid << " still running";
  EXPECT_FALSE(canOpenDisplay(display));
}

TEST(DisplayGuard, MissingXvfbGivesOneLineInstallHint) {
  ::unsetenv("DISPLAY");
  DisplayGuardOptions o;
  o.xvfb = "Xvfb-that-does-not-exist";
  DisplayGuard guard(o);
  EXPECT_FALSE(guard.ok());
  EXPECT_NE(guard.message().find("install the xvfb package"), std::string::npos) << guard.message();
  EXPECT_EQ(guard.message().find('\n'), std::string::npos);
  EXPECT_EQ(std::getenv("DISPLAY"), nullptr);
}

TEST(DisplayGuard, UnusableDisplayFallsBackToXvfb) {
  ::setenv("DISPLAY", ":7319", 1);  // nothing listens there
  {
    DisplayGuard guard;
    ASSERT_TRUE(guard.ok()) << guard.message();
    EXPECT_TRUE(guard.startedXvfb());
  }
  ASSERT_NE(std::getenv("DISPLAY"), nullptr);
  EXPECT_EQ(std::string(std::getenv("DISPLAY")), ":7319");
  ::unsetenv("DISPLAY");
}

}  // namespace
}  // namespace rsvio::viz
