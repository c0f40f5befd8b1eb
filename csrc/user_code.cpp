// What a user's code compiled apart may not do silently (user_code.hpp). The handlers write with
// write(2) only and read nothing but atomics, thread-locals and strings kept for the process's
// life: they may run in a signal's context.
#include "user_code.hpp"

#include <dlfcn.h>
#include <semaphore.h>
#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <map>
#include <mutex>
#include <thread>

#include "types.hpp"

namespace nnrobust {
namespace {

// What the calling thread runs now (exits and crashes are said in the thread that made them),
// and the last call into user code any thread entered (the watchdog's: the stuck thread is not
// its own). initial-exec: a signal handler may read them.
thread_local const char *running_label __attribute__((tls_model("initial-exec"))) = nullptr;
thread_local const char *running_phase __attribute__((tls_model("initial-exec"))) = nullptr;
std::atomic<const char *> last_label{nullptr};
std::atomic<int> depth{0};               // calls into user code in progress, every thread
std::atomic<unsigned long> entries{0};   // calls into user code begun so far

constexpr int exit_code = 70;  // EX_SOFTWARE: the process was ended by the law, not by nnrobust
constexpr int stop_code = 130;

void say(const char *text) {
  if (text == nullptr) return;
  size_t left = std::strlen(text);
  while (left > 0) {
    const ssize_t n = ::write(STDERR_FILENO, text, left);
    if (n < 0) {
      if (errno == EINTR) continue;
      return;
    }
    text += n;
    left -= static_cast<size_t>(n);
  }
}

void say_number(long value) {
  char digits[24];
  int i = sizeof(digits) - 1;
  digits[i] = '\0';
  unsigned long v = value < 0 ? 0UL - static_cast<unsigned long>(value) : static_cast<unsigned long>(value);
  do {
    digits[--i] = static_cast<char>('0' + v % 10);
    v /= 10;
  } while (v != 0 && i > 1);
  if (value < 0) digits[--i] = '-';
  say(digits + i);
}

const char *signal_text(int sig) {
  switch (sig) {
    case SIGSEGV: return "SIGSEGV (an invalid memory access: a null or dangling pointer, an index out of bounds)";
    case SIGBUS: return "SIGBUS (an invalid memory access)";
    case SIGFPE: return "SIGFPE (an integer division by zero or an arithmetic trap)";
    case SIGILL: return "SIGILL (an illegal instruction: a trap, or code built for another CPU)";
    case SIGABRT: return "SIGABRT (abort: a failed assertion or an uncaught exception)";
    case SIGINT: return "SIGINT";
    case SIGTERM: return "SIGTERM";
    case SIGHUP: return "SIGHUP";
    default: return "a signal";
  }
}

std::mutex names_lock;
std::map<std::string, const char *> &library_names() {
  static auto *names = new std::map<std::string, const char *>;  // never freed: read at exit
  return *names;
}

// The label of the library that holds `where` (an exit outside any UserCodeScope).
const char *label_at(const void *where) {
  Dl_info info;
  if (where == nullptr || dladdr(where, &info) == 0 || info.dli_fname == nullptr) return nullptr;
  const std::lock_guard<std::mutex> hold(names_lock);
  const auto it = library_names().find(info.dli_fname);
  return it == library_names().end() ? user_label(std::string("code compiled apart (") + info.dli_fname + ")")
                                     : it->second;
}

[[noreturn]] void ended(const char *call, bool with_code, int code, const void *where) {
  std::fflush(stdout);
  std::fflush(stderr);
  const char *label = running_label, *phase = running_phase;
  if (label == nullptr) label = label_at(where), phase = nullptr;
  say("nnrobust: ");
  say(label ? label : "a library compiled apart");
  say(" called ");
  say(call);
  say("(");
  if (with_code) say_number(code);
  say(")");
  if (phase) say(" inside "), say(phase);
  say(": a law may not end the process; the run is lost (exit code 70)\n");
  ::_exit(exit_code);
}

void at_exit() {  // exit() from the thread running user code, not through its library's wrapper
  if (running_label == nullptr) return;
  say("nnrobust: ");
  say(running_label);
  say(" ended the process (exit) inside ");
  say(running_phase);
  say(": a law may not end the process; the run is lost (exit code 70)\n");
  ::_exit(exit_code);
}

constexpr int crash_signals[] = {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT};
struct sigaction crash_previous[5];

void on_crash(int sig, siginfo_t *info, void *) {
  int i = 0;
  while (i < 4 && crash_signals[i] != sig) ++i;
  if (running_label != nullptr) {
    say("nnrobust: ");
    say(running_label);
    say(" crashed inside ");
    say(running_phase);
    say(": ");
    say(signal_text(sig));
    say("\n");
  }
  // the previous action back (SIG_DFL, or faulthandler's), then the signal again: a fault
  // happens again when this handler returns; a signal sent (kill, raise, abort) is raised again
  sigaction(sig, &crash_previous[i], nullptr);
  if (info == nullptr || info->si_code <= 0 || sig == SIGABRT) raise(sig);
}

constexpr int stop_signals[] = {SIGINT, SIGTERM, SIGHUP};
struct sigaction stop_previous[3];
sem_t stop_posted;
std::atomic<int> stop_signal{0};
std::atomic<int> watched_runs{0};
std::mutex stop_lock;
int stop_users = 0;

void on_stop(int sig, siginfo_t *info, void *context) {
  const int saved = errno;
  int i = 0;
  while (i < 2 && stop_signals[i] != sig) ++i;
  const struct sigaction &previous = stop_previous[i];
  if (previous.sa_flags & SA_SIGINFO) {
    if (previous.sa_sigaction != nullptr) previous.sa_sigaction(sig, info, context);
  } else if (previous.sa_handler == SIG_DFL) {  // the default action (the process ends), as before
    sigaction(sig, &previous, nullptr);
    raise(sig);
    errno = saved;
    return;
  } else if (previous.sa_handler == SIG_IGN) {
    errno = saved;
    return;
  } else {
    previous.sa_handler(sig);  // Python's: it notes the signal for the interpreter
  }
  stop_signal.store(sig);
  sem_post(&stop_posted);
  errno = saved;
}

// After a stop signal, while a run of user code goes on: a call into it that has not returned
// after stop_grace_seconds ends the process (the loop polls the signal between steps only).
void watch() {
  using Clock = std::chrono::steady_clock;
  for (;;) {
    while (sem_wait(&stop_posted) != 0) {
    }
    const int sig = stop_signal.load();
    unsigned long seen = entries.load();
    Clock::time_point since = Clock::now();
    while (watched_runs.load() > 0) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      const unsigned long now = entries.load();
      if (depth.load() == 0 || now != seen) {  // the call returned: the loop sees the signal
        seen = now;
        since = Clock::now();
        continue;
      }
      if (Clock::now() - since >= std::chrono::seconds(stop_grace_seconds)) {
        say("nnrobust: ");
        say(last_label.load());
        say(" did not return within ");
        say_number(stop_grace_seconds);
        say(" s after the stop signal (");
        say(signal_text(sig));
        say("): the run is ended without its partial result\n");
        ::_exit(stop_code);
      }
    }
  }
}

}  // namespace

UserCodeScope::UserCodeScope(const char *label, const char *phase) noexcept
    : label_(running_label), phase_(running_phase) {
  running_label = label;
  running_phase = phase;
  last_label.store(label, std::memory_order_relaxed);
  entries.fetch_add(1, std::memory_order_relaxed);
  depth.fetch_add(1, std::memory_order_relaxed);
}

UserCodeScope::~UserCodeScope() {
  depth.fetch_sub(1, std::memory_order_relaxed);
  running_label = label_;
  running_phase = phase_;
}

const char *user_label(const std::string &label) {
  static std::mutex lock;
  static auto *labels = new std::deque<std::string>;  // never freed: a signal handler may read one
  const std::lock_guard<std::mutex> hold(lock);
  for (const std::string &known : *labels)
    if (known == label) return known.c_str();
  labels->push_back(label);
  return labels->back().c_str();
}

void name_library(const std::string &path, const char *label) {
  static std::once_flag installed;
  std::call_once(installed, []() {
    std::atexit(&at_exit);
    std::at_quick_exit(&at_exit);
    struct sigaction action {};
    action.sa_sigaction = &on_crash;
    action.sa_flags = SA_SIGINFO | SA_ONSTACK;
    sigemptyset(&action.sa_mask);
    for (int i = 0; i < 5; ++i) sigaction(crash_signals[i], &action, &crash_previous[i]);
  });
  const std::lock_guard<std::mutex> hold(names_lock);
  library_names()[path] = label;
}

StopWatchdog::StopWatchdog() {
  static std::once_flag started;
  std::call_once(started, []() {
    sem_init(&stop_posted, 0, 0);
    std::thread(&watch).detach();
  });
  const std::lock_guard<std::mutex> hold(stop_lock);
  watched_runs.fetch_add(1);
  if (stop_users++ > 0) return;
  struct sigaction action {};
  action.sa_sigaction = &on_stop;
  action.sa_flags = SA_SIGINFO | SA_ONSTACK;
  sigemptyset(&action.sa_mask);
  for (int i = 0; i < 3; ++i) sigaction(stop_signals[i], &action, &stop_previous[i]);
}

StopWatchdog::~StopWatchdog() {
  const std::lock_guard<std::mutex> hold(stop_lock);
  watched_runs.fetch_sub(1);
  if (--stop_users > 0) return;
  for (int i = 0; i < 3; ++i) {  // the handlers they had, unless someone has changed them since
    struct sigaction now {};
    sigaction(stop_signals[i], nullptr, &now);
    if ((now.sa_flags & SA_SIGINFO) && now.sa_sigaction == &on_stop) sigaction(stop_signals[i], &stop_previous[i], nullptr);
  }
}

}  // namespace nnrobust

// The wrappers a user's library is linked with (-Wl,--wrap=exit, ...; nnrobust/native_law.py):
// its calls to these functions come here, resolved against this module's exported symbols.
extern "C" {
[[noreturn]] NNROBUST_API void __wrap_exit(int code) {
  nnrobust::ended("exit", true, code, __builtin_return_address(0));
}
[[noreturn]] NNROBUST_API void __wrap__exit(int code) {
  nnrobust::ended("_exit", true, code, __builtin_return_address(0));
}
[[noreturn]] NNROBUST_API void __wrap__Exit(int code) {
  nnrobust::ended("_Exit", true, code, __builtin_return_address(0));
}
[[noreturn]] NNROBUST_API void __wrap_quick_exit(int code) {
  nnrobust::ended("quick_exit", true, code, __builtin_return_address(0));
}
[[noreturn]] NNROBUST_API void __wrap_abort(void) { nnrobust::ended("abort", false, 0, __builtin_return_address(0)); }
}
