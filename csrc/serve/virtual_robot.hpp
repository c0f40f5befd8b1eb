// The virtual robot (`nnrobust serve`, docs/serve.md): the compiled plant of an experiment paced by
// the wall clock at its control period, speaking protocol.h over UDP to a controller in another
// process, with a real arm's watchdog. The twin of nothing in Python: its plant is the compiled
// loop's (SteppedLoop without its law), so a run whose commands all arrive in time is the
// simulated run of the same law.
#pragma once

#include <map>
#include <string>
#include <utility>
#include <vector>

#include "../closed_loop.hpp"

namespace nnrobust {

struct ServeOptions {
  std::string host = "127.0.0.1";  // the address it listens on
  int port = 0;                    // 0: a free port (VirtualRobot::port says which)
  double wait_seconds = 30.0;      // for the controller's HELLO
  int watchdog = 20;               // periods without a command before the protective stop
  bool realtime = false;           // run the robot's thread under SCHED_FIFO (where allowed)
  // Lockstep: no wall clock; each period waits for its command (up to wait_seconds) and the next
  // starts as soon as it came. The served run is then the simulated run of the same law, exactly.
  bool lockstep = false;
};

struct ServeReport {
  long periods = 0;   // control periods run
  long accepted = 0;  // commands applied in time
  long misses = 0;    // periods without a command in time (the last command held)
  std::map<std::string, long> rejected;               // datagrams not applied, by reason
  std::vector<std::pair<double, std::string>> events;  // the first ones: (t, reason)
  std::vector<double> latency;   // [s] state sent -> its command received, per accepted command
  std::vector<double> lateness;  // [s] state sent - its scheduled instant, per period
  std::string stopped;           // why the robot stopped early ("" when it ran to the end)
  bool connected = false;        // a controller said HELLO
  std::string scheduling = "normal";  // "SCHED_FIFO 80", or why real-time scheduling was refused
};

class VirtualRobot {
 public:
  // binds the socket (std::runtime_error naming the address when it cannot)
  VirtualRobot(LoadedModel &plant, const LoopSpec &spec, const ServeOptions &options);
  ~VirtualRobot();
  VirtualRobot(const VirtualRobot &) = delete;
  VirtualRobot &operator=(const VirtualRobot &) = delete;

  int port() const { return port_; }
  // Waits for a controller, then runs the experiment in real time; `interrupted()` is polled
  // (Ctrl-C, SIGTERM end the run, marked interrupted).
  ServeReport run(bool (*interrupted)());
  LoopTrace finish() { return loop_.finish(); }

 private:
  const LoopSpec &spec_;
  ServeOptions options_;
  SteppedLoop loop_;
  int fd_ = -1;
  int port_ = 0;
};

}  // namespace nnrobust
