// Bounded child-process pool (rsvio/eval/process_pool.h).
#include "rsvio/eval/process_pool.h"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <deque>
#include <thread>

extern char** environ;

namespace rsvio::eval {
namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

struct Running {
  size_t index;
  pid_t pid;
  Clock::time_point start;
};

// Starts one child; returns its pid or fills `error` and returns -1.
pid_t spawnChild(const ChildSpec& spec, std::string& error) {
  if (spec.argv.empty()) {
    error = "empty command";
    return -1;
  }
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  const char* log = spec.log_path.empty() ? "/dev/null" : spec.log_path.c_str();
  posix_spawn_file_actions_addopen(&fa, STDOUT_FILENO, log, O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&fa, STDOUT_FILENO, STDERR_FILENO);
  std::vector<char*> argv;
  argv.reserve(spec.argv.size() + 1);
  for (const auto& a : spec.argv) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  // Own process group: a Ctrl-C on the terminal goes to the parent only, which stops the children.
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  posix_spawnattr_setpgroup(&attr, 0);
  // Default dispositions and an empty mask for SIGINT/SIGTERM, whatever the parent installed.
  sigset_t def, empty;
  sigemptyset(&def);
  sigaddset(&def, SIGINT);
  sigaddset(&def, SIGTERM);
  sigemptyset(&empty);
  posix_spawnattr_setsigdefault(&attr, &def);
  posix_spawnattr_setsigmask(&attr, &empty);
  posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETPGROUP | POSIX_SPAWN_SETSIGDEF | POSIX_SPAWN_SETSIGMASK);
  pid_t pid = -1;
  const int rc = posix_spawn(&pid, argv[0], &fa, &attr, argv.data(), environ);
  posix_spawnattr_destroy(&attr);
  posix_spawn_file_actions_destroy(&fa);
  if (rc != 0) {
    error = std::strerror(rc);
    return -1;
  }
  return pid;
}

// The child and whatever it started (it leads its own process group).
void signalGroup(pid_t pid, int sig) {
  if (kill(-pid, sig) != 0) kill(pid, sig);
}

}  // namespace

std::string ChildOutcome::describe() const {
  switch (kind) {
    case Kind::kExited: return "exit code " + std::to_string(code);
    case Kind::kSignaled: {
      const char* name = strsignal(code);
      return "killed by signal " + std::to_string(code) + (name ? std::string(" (") + name + ")" : std::string());
    }
    case Kind::kTimedOut: {
      char buf[64];
      std::snprintf(buf, sizeof(buf), "timed out after %g s (killed)", timeout_s);
      return buf;
    }
    case Kind::kNotStarted: return "not started (interrupted)";
    default: return "could not start: " + spawn_error;
  }
}

std::vector<ChildOutcome> runChildProcesses(const std::vector<ChildSpec>& children, const PoolOptions& options,
                                            const std::function<void(size_t)>& on_start,
                                            const std::function<void(size_t, const ChildOutcome&)>& on_done) {
  std::vector<ChildOutcome> outcomes(children.size());
  const size_t max_workers = static_cast<size_t>(std::max(1, options.max_workers));
  size_t next = 0;
  std::deque<Running> running;
  auto finish = [&](size_t i, ChildOutcome o) {
    o.timeout_s = options.timeout_s;
    outcomes[i] = o;
    if (on_done) on_done(i, outcomes[i]);
  };
  int stop_sent = 0;  // the stop level already acted on
  while (next < children.size() || !running.empty()) {
    const int level = options.stop_level ? options.stop_level() : 0;
    if (level > stop_sent) {
      for (const Running& r : running) signalGroup(r.pid, level >= 2 ? SIGKILL : SIGTERM);
      stop_sent = level;
    }
    if (stop_sent > 0) {
      while (next < children.size()) {
        ChildOutcome o;
        o.kind = ChildOutcome::Kind::kNotStarted;
        finish(next++, o);
      }
    }
    while (next < children.size() && running.size() < max_workers) {
      const size_t i = next++;
      if (on_start) on_start(i);
      std::string error;
      const auto t0 = Clock::now();
      const pid_t pid = spawnChild(children[i], error);
      if (pid < 0) {
        ChildOutcome o;
        o.kind = ChildOutcome::Kind::kSpawnFailed;
        o.spawn_error = error;
        finish(i, o);
        continue;
      }
      running.push_back({i, pid, t0});
    }
    bool any_finished = false;
    for (auto it = running.begin(); it != running.end();) {
      int status = 0;
      const pid_t r = waitpid(it->pid, &status, WNOHANG);
      ChildOutcome o;
      bool done = false;
      if (r == it->pid) {
        done = true;
        if (WIFSIGNALED(status)) {
          o.kind = ChildOutcome::Kind::kSignaled;
          o.code = WTERMSIG(status);
        } else {
          o.kind = ChildOutcome::Kind::kExited;
          o.code = WEXITSTATUS(status);
        }
      } else if (r < 0 && errno != EINTR) {
        done = true;  // not our child any more (should not happen); report rather than spin
        o.kind = ChildOutcome::Kind::kSpawnFailed;
        o.spawn_error = std::string("lost track of the child: ") + std::strerror(errno);
      } else if (options.timeout_s > 0 && secondsSince(it->start) > options.timeout_s) {
        signalGroup(it->pid, SIGKILL);
        waitpid(it->pid, &status, 0);
        done = true;
        o.kind = ChildOutcome::Kind::kTimedOut;
      }
      if (done) {
        o.wall_s = secondsSince(it->start);
        o.stopped = stop_sent > 0;
        const size_t i = it->index;
        it = running.erase(it);
        finish(i, o);
        any_finished = true;
      } else {
        ++it;
      }
    }
    if (!any_finished && !running.empty()) std::this_thread::sleep_for(std::chrono::milliseconds(options.poll_ms));
  }
  return outcomes;
}

}  // namespace rsvio::eval
