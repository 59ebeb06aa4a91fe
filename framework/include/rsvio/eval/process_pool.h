// A bounded pool of child processes, for `rsvio compare`'s grid of runs.
//
// Each child is started with posix_spawn (no shell), stdin from /dev/null, stdout and stderr both
// appended to its own log file, and the parent's environment. At most max_workers run at once; the
// caller's thread polls them (no threads, no signal handlers, no global state) and kills a child with
// SIGKILL once it has run longer than timeout_s. A child that crashes (signal), exits non-zero, times
// out or cannot be started is reported as such; nothing a child does can throw or crash the parent.
// Each child leads its own process group, so Ctrl-C on the terminal reaches only the caller, which
// decides (PoolOptions::stop_level): level 1 sends SIGTERM to every running child once and starts no
// more (an `rsvio run` child then stops at its next frame and writes its outputs), level 2 sends SIGKILL.
// The pool still waits for every started child, so none is left running or orphaned.
#pragma once
#include <functional>
#include <string>
#include <vector>

namespace rsvio::eval {

struct ChildSpec {
  std::vector<std::string> argv;  // argv[0] is the program path (not searched on PATH)
  std::string log_path;           // created or truncated; its folder must exist
};

struct ChildOutcome {
  enum class Kind { kExited, kSignaled, kTimedOut, kSpawnFailed, kNotStarted };
  Kind kind = Kind::kSpawnFailed;
  int code = -1;            // exit status (kExited) or signal number (kSignaled)
  std::string spawn_error;  // kSpawnFailed: why
  double wall_s = 0;        // start to end
  double timeout_s = 0;     // the limit that applied (for the message)
  bool stopped = false;     // the pool had sent it the stop signal (PoolOptions::stop_level)

  bool ok() const { return kind == Kind::kExited && code == 0; }
  // "exit code 3", "killed by signal 11 (Segmentation fault)", "timed out after 5 s (killed)",
  // "could not start: No such file or directory", "not started (interrupted)".
  std::string describe() const;
};

struct PoolOptions {
  int max_workers = 2;
  double timeout_s = 0;  // <= 0: no limit
  int poll_ms = 10;
  // Polled between polls of the children: 0 run on, 1 stop (SIGTERM to the running children, start no
  // more: those get Kind::kNotStarted), 2 kill (SIGKILL to the running children).
  std::function<int()> stop_level;
};

// Runs every child and returns their outcomes in the order of `children`. on_start(i) just before child
// i is spawned and on_done(i, outcome) as it finishes, both on the calling thread; on_done's order is
// completion order.
std::vector<ChildOutcome> runChildProcesses(const std::vector<ChildSpec>& children, const PoolOptions& options,
                                            const std::function<void(size_t)>& on_start = {},
                                            const std::function<void(size_t, const ChildOutcome&)>& on_done = {});

}  // namespace rsvio::eval
