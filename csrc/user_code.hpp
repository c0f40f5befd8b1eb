// A user's code compiled apart (a law in C++, a twin: nnrobust/native_law.py) runs inside the
// compiled loop's process; what it may do there that Python cannot catch is caught here, so that
// the run ends with one line naming the law and a nonzero exit, never silently:
// - exit, _exit, _Exit, quick_exit or abort called by its library (linked with --wrap=NAME, the
//   wrappers defined in user_code.cpp) or by anything it calls (atexit and at_quick_exit
//   handlers): one line, then _exit(70);
// - a crash (SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT) in the thread running it: one line, then
//   the previous action (a signal death; pytest's faulthandler still runs);
// - a stop signal (Ctrl-C, SIGTERM, SIGHUP) while it does not return: Python's handler runs as
//   before, and if the call running at the signal has not returned 2 s later, one line and
//   _exit(130).
// Only runs of such code take any of it: a shipped law's step is unchanged.
#pragma once

#include <atomic>
#include <stdexcept>
#include <string>

namespace nnrobust {

// Raised for a user law's exception, a torque, state or signals of the wrong size, or a missing
// parameter: its message names the law and its file (nnrobust._loop.UserLawError in Python).
struct UserLawError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The calling thread runs the user's code `label` ("the law TaskPD (/home/me/task_pd.cpp)"; a
// string kept for the process's life, user_label) in `phase` ("its compute") for the block.
class UserCodeScope {
 public:
  UserCodeScope(const char *label, const char *phase) noexcept;
  ~UserCodeScope();
  UserCodeScope(const UserCodeScope &) = delete;
  UserCodeScope &operator=(const UserCodeScope &) = delete;

 private:
  const char *label_, *phase_;
};

// A label kept for the process's life (never freed: a signal handler may read it).
const char *user_label(const std::string &label);

// The library at `path` (as dlopen was given it) is the user's code `label`: an exit it makes
// outside any UserCodeScope is said with that label. Installs the crash handlers and the exit
// handlers the first time.
void name_library(const std::string &path, const char *label);

// For the length of a run of user code: Ctrl-C, SIGTERM and SIGHUP go first to the handlers
// they had (Python's), then arm the watchdog. Runs may nest or overlap (threads): the handlers
// are installed by the first and restored by the last.
class StopWatchdog {
 public:
  StopWatchdog();
  ~StopWatchdog();
  StopWatchdog(const StopWatchdog &) = delete;
  StopWatchdog &operator=(const StopWatchdog &) = delete;
};

// Seconds a call into user code may go on after a stop signal before the process is ended.
constexpr int stop_grace_seconds = 2;

}  // namespace nnrobust
