// DisplayGuard: an X display for VTK's off-screen rendering, for as long as the guard lives.
//
// Why: Debian's VTK 9.1 is built for X (vtkXOpenGLRenderWindow); even off-screen it opens an X display
// and crashes rather than fails cleanly when there is none. So nothing in viz/ touches VTK before a
// guard says ok().
//
// Contract:
// - If $DISPLAY is set and can be opened, it is used as is (nothing started).
// - Otherwise the guard starts its own Xvfb on the first free display number from options.first_display
//   (skipping numbers whose /tmp/.X<n>-lock or /tmp/.X11-unix/X<n> exists, and moving on when Xvfb
//   exits because another process took the number), with -nolisten tcp; it waits until the socket
//   /tmp/.X11-unix/X<n> exists and the display opens, then sets $DISPLAY for this process.
// - The destructor stops that Xvfb (SIGTERM, then SIGKILL) and restores $DISPLAY. The Xvfb child also
//   gets SIGTERM if the thread that created the guard dies (PR_SET_PDEATHSIG), so a crash leaves no server.
// - Never throws: ok() says whether a display is available, message() says why not in one line
//   (e.g. "no X display and no Xvfb on PATH: install the xvfb package (apt-get install xvfb)").
// - $DISPLAY is process-wide state: create guards from one thread, before any VTK window, and destroy
//   every VTK window before the guard. Guards nest (an inner guard finds the outer's display and uses it).
#pragma once
#include <string>
#include <sys/types.h>

namespace rsvio::viz {

struct DisplayGuardOptions {
  std::string xvfb = "Xvfb";       // program name (searched on PATH) or a path
  int first_display = 99;          // first display number tried
  int tries = 100;                 // display numbers tried
  double timeout_s = 10.0;         // per start attempt
  std::string screen = "1920x1200x24";
  bool ignore_env_display = false; // tests: start Xvfb even when $DISPLAY works
};

class DisplayGuard {
 public:
  explicit DisplayGuard(const DisplayGuardOptions& options = {});
  ~DisplayGuard();
  DisplayGuard(const DisplayGuard&) = delete;
  DisplayGuard& operator=(const DisplayGuard&) = delete;

  bool ok() const { return ok_; }
  const std::string& message() const { return message_; }  // why not ok, or how the display was obtained
  const std::string& display() const { return display_; }  // e.g. ":99"
  bool startedXvfb() const { return xvfb_pid_ > 0; }
  pid_t xvfbPid() const { return xvfb_pid_; }

 private:
  bool tryStart(const std::string& xvfb_path, int n, const DisplayGuardOptions& options, std::string& why);
  void stop();

  bool ok_ = false;
  std::string message_;
  std::string display_;
  pid_t xvfb_pid_ = -1;
  bool had_env_display_ = false;
  std::string previous_display_;
};

// True when an X connection to `display` (e.g. ":0") can be opened now.
bool canOpenDisplay(const std::string& display);

}  // namespace rsvio::viz
