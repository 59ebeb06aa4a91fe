// DisplayGuard (rsvio/viz/display_guard.h): use $DISPLAY or start and own an Xvfb.
#include "rsvio/viz/display_guard.h"

#include <X11/Xlib.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <cstdlib>
#include <sstream>
#include <thread>
#include <vector>

namespace rsvio::viz {
namespace {

bool pathExists(const std::string& p) {
  struct stat st {};
  return ::stat(p.c_str(), &st) == 0;
}

// The program as given when it has a '/', else the first executable of that name on $PATH.
std::string findProgram(const std::string& name) {
  if (name.find('/') != std::string::npos) return ::access(name.c_str(), X_OK) == 0 ? name : "";
  const char* path = std::getenv("PATH");
  std::stringstream ss(path ? path : "/usr/local/bin:/usr/bin:/bin");
  std::string dir;
  while (std::getline(ss, dir, ':')) {
    if (dir.empty()) continue;
    const std::string full = dir + "/" + name;
    if (::access(full.c_str(), X_OK) == 0) return full;
  }
  return "";
}

// Reaps the child if it has exited; true when it is still running.
bool childAlive(pid_t pid) {
  int status = 0;
  return ::waitpid(pid, &status, WNOHANG) == 0;
}

void killAndReap(pid_t pid) {
  if (pid <= 0) return;
  ::kill(pid, SIGTERM);
  for (int i = 0; i < 100; ++i) {  // up to 2 s for a clean exit (Xvfb removes its lock and socket)
    if (!childAlive(pid)) return;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ::kill(pid, SIGKILL);
  int status = 0;
  ::waitpid(pid, &status, 0);
}

}  // namespace

// The pid in /tmp/.X<n>-lock (Xvfb writes it as text when it claims display n), -1 if none.
static long lockPid(int n) {
  std::ifstream in("/tmp/.X" + std::to_string(n) + "-lock");
  long pid = -1;
  if (!(in >> pid)) return -1;
  return pid;
}

bool canOpenDisplay(const std::string& display) {
  if (display.empty()) return false;
  Display* d = XOpenDisplay(display.c_str());
  if (!d) return false;
  XCloseDisplay(d);
  return true;
}

DisplayGuard::DisplayGuard(const DisplayGuardOptions& options) {
  const char* env = std::getenv("DISPLAY");
  had_env_display_ = env != nullptr;
  if (env) previous_display_ = env;
  if (!options.ignore_env_display && env && *env) {
    if (canOpenDisplay(env)) {
      ok_ = true;
      display_ = env;
      message_ = std::string("using DISPLAY=") + env;
      return;
    }
  }
  const std::string xvfb = findProgram(options.xvfb);
  if (xvfb.empty()) {
    message_ = std::string(env && *env ? "DISPLAY=" + std::string(env) + " cannot be opened" : "no X display (DISPLAY unset)") +
               " and no " + options.xvfb + " found: install the xvfb package (apt-get install xvfb)";
    return;
  }
  std::string why = "no free display number";
  for (int k = 0; k < options.tries; ++k) {
    const int n = options.first_display + k;
    if (pathExists("/tmp/.X" + std::to_string(n) + "-lock") || pathExists("/tmp/.X11-unix/X" + std::to_string(n))) continue;
    if (tryStart(xvfb, n, options, why)) {
      ok_ = true;
      message_ = "started " + xvfb + " on " + display_;
      return;
    }
  }
  message_ = "could not start " + xvfb + ": " + why;
}

bool DisplayGuard::tryStart(const std::string& xvfb_path, int n, const DisplayGuardOptions& options,
                            std::string& why) {
  const std::string disp = ":" + std::to_string(n);
  // Everything the child needs is prepared before fork: after it, only async-signal-safe calls.
  std::vector<std::string> args = {xvfb_path, disp, "-screen", "0", options.screen, "-nolisten", "tcp", "-noreset"};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid < 0) {
    why = "fork failed";
    return false;
  }
  if (pid == 0) {
    ::prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (::getppid() != parent) ::_exit(127);  // the parent died before prctl took effect
    const int devnull = ::open("/dev/null", O_RDWR);
    if (devnull >= 0) {
      ::dup2(devnull, 0);
      ::dup2(devnull, 1);
      ::dup2(devnull, 2);
    }
    ::setpgid(0, 0);  // its own group: a terminal's Ctrl-C reaches us first, and we clean up
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  const std::string socket = "/tmp/.X11-unix/X" + std::to_string(n);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(options.timeout_s);
  while (std::chrono::steady_clock::now() < deadline) {
    if (!childAlive(pid)) {
      why = "Xvfb exited at start on " + disp + " (display taken?)";
      return false;
    }
    if (pathExists(socket) && canOpenDisplay(disp)) {
      // Two processes can pick the same free number at once (parallel tests, batch renders): the
      // display that opens may be the other's, whose Xvfb goes when that process ends. Ours only if the
      // X lock file holds our child's pid (Xvfb writes it there when it claims the number).
      if (lockPid(n) != pid) {
        killAndReap(pid);
        why = "display " + disp + " was claimed by another process's Xvfb";
        return false;
      }
      xvfb_pid_ = pid;
      display_ = disp;
      ::setenv("DISPLAY", disp.c_str(), 1);
      return true;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  killAndReap(pid);
  why = "Xvfb did not open " + disp + " within " + std::to_string(options.timeout_s) + " s";
  return false;
}

void DisplayGuard::stop() {
  if (xvfb_pid_ <= 0) return;
  killAndReap(xvfb_pid_);
  xvfb_pid_ = -1;
  if (had_env_display_) ::setenv("DISPLAY", previous_display_.c_str(), 1);
  else ::unsetenv("DISPLAY");
}

DisplayGuard::~DisplayGuard() { stop(); }

}  // namespace rsvio::viz
