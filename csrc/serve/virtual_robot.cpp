#include "virtual_robot.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <pthread.h>
#include <sched.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "../controllers.hpp"
#include "protocol.h"

namespace nnrobust {
namespace {

constexpr std::size_t max_events = 100;   // the first rejections kept with their time
constexpr std::size_t header_size = sizeof(nnrobust_serve_header);
static_assert(header_size == 32, "the protocol's header is 32 bytes");

double seconds(const timespec &t) { return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec); }

timespec now() {
  timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return t;
}

timespec at(double s) {
  timespec t;
  t.tv_sec = static_cast<time_t>(std::floor(s));
  t.tv_nsec = static_cast<long>((s - std::floor(s)) * 1e9);
  if (t.tv_nsec >= 1000000000L) {
    t.tv_sec += 1;
    t.tv_nsec -= 1000000000L;
  }
  return t;
}

bool same(const sockaddr_in &a, const sockaddr_in &b) {
  return a.sin_addr.s_addr == b.sin_addr.s_addr && a.sin_port == b.sin_port;
}

nnrobust_serve_header header(uint16_t type, uint64_t seq, double t, uint32_t n) {
  nnrobust_serve_header h{};
  h.magic = NNROBUST_SERVE_MAGIC;
  h.version = NNROBUST_SERVE_VERSION;
  h.type = type;
  h.seq = seq;
  h.t = t;
  h.n = n;
  return h;
}

}  // namespace

VirtualRobot::VirtualRobot(LoadedModel &plant, const LoopSpec &spec, const ServeOptions &options)
    : spec_(spec), options_(options), loop_(plant, nullptr, spec, false) {
  fd_ = socket(AF_INET, SOCK_DGRAM, 0);
  if (fd_ < 0) throw std::runtime_error(std::string("serve: no UDP socket: ") + std::strerror(errno));
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(static_cast<uint16_t>(options.port));
  if (inet_pton(AF_INET, options.host.c_str(), &address.sin_addr) != 1) {
    close(fd_);
    throw std::invalid_argument("serve: --host " + options.host + " is not an IPv4 address");
  }
  if (bind(fd_, reinterpret_cast<sockaddr *>(&address), sizeof(address)) != 0) {
    const std::string why = std::strerror(errno);
    close(fd_);
    throw std::runtime_error("serve: cannot listen on " + options.host + ":" + std::to_string(options.port) + " (" +
                             why + ")");
  }
  socklen_t size = sizeof(address);
  getsockname(fd_, reinterpret_cast<sockaddr *>(&address), &size);
  port_ = ntohs(address.sin_port);
}

VirtualRobot::~VirtualRobot() {
  if (fd_ >= 0) close(fd_);
}

ServeReport VirtualRobot::run(bool (*interrupted)()) {
  ServeReport report;
  const int n = static_cast<int>(loop_.measured_q().size());
  const double period = spec_.period;
  const std::size_t state_size = header_size + 2 * sizeof(double) * static_cast<std::size_t>(n);
  const std::size_t command_size = header_size + sizeof(double) * static_cast<std::size_t>(n);
  std::vector<unsigned char> in(65536), out(state_size);
  sockaddr_in client{};
  bool have_client = false;
  long k = 0;
  Vector command = Vector::Zero(n), received(n);
  bool got = false;  // a command for period k has been accepted
  double sent = 0.0;  // when STATE k left
  report.latency.reserve(static_cast<std::size_t>(spec_.steps));
  report.lateness.reserve(static_cast<std::size_t>(spec_.steps));
  const auto reject = [&](const std::string &reason) {
    ++report.rejected[reason];
    if (report.events.size() < max_events) report.events.emplace_back(static_cast<double>(k) * period, reason);
  };
  // Every datagram waiting on the socket: a HELLO (before the run), or a COMMAND for period k.
  const auto drain = [&](bool running) {
    for (;;) {
      sockaddr_in from{};
      socklen_t from_size = sizeof(from);
      const ssize_t size =
          recvfrom(fd_, in.data(), in.size(), MSG_DONTWAIT, reinterpret_cast<sockaddr *>(&from), &from_size);
      if (size < 0) return;  // nothing more (EAGAIN), or an error the next poll meets again
      const double arrived = seconds(now());
      if (have_client && !same(from, client)) {
        reject("another sender than the controller");
        continue;
      }
      if (static_cast<std::size_t>(size) < header_size) {
        reject("a datagram shorter than the header");
        continue;
      }
      nnrobust_serve_header h;
      std::memcpy(&h, in.data(), header_size);
      if (h.magic != NNROBUST_SERVE_MAGIC || h.version != NNROBUST_SERVE_VERSION) {
        reject("a wrong magic number or protocol version");
        continue;
      }
      if (!running) {
        if (h.type == NNROBUST_SERVE_HELLO) {
          client = from;
          have_client = true;
        } else {
          reject("a datagram before HELLO");
        }
        continue;
      }
      if (h.type != NNROBUST_SERVE_COMMAND) {
        reject("not a COMMAND");
        continue;
      }
      if (h.n != static_cast<uint32_t>(n) || static_cast<std::size_t>(size) != command_size) {
        reject("a COMMAND of the wrong size (needs " + std::to_string(n) + " torques)");
        continue;
      }
      if (h.seq < static_cast<uint64_t>(k)) {
        reject("a COMMAND of a past period (late, replayed or out of order)");
        continue;
      }
      if (h.seq > static_cast<uint64_t>(k)) {
        reject("a COMMAND of a period not yet measured");
        continue;
      }
      if (got) {
        reject("a second COMMAND for one period");
        continue;
      }
      std::memcpy(received.data(), in.data() + header_size, sizeof(double) * static_cast<std::size_t>(n));
      if (!received.allFinite()) {
        reject("a COMMAND with a torque that is not finite");
        continue;
      }
      command = received;
      got = true;
      report.latency.push_back(arrived - sent);
    }
  };
  // wait for the controller
  const double give_up = seconds(now()) + options_.wait_seconds;
  while (!have_client) {
    const double left = give_up - seconds(now());
    if (left <= 0.0) {
      report.stopped = "no controller said HELLO within " + std::to_string(options_.wait_seconds) + " s";
      loop_.end("interrupted");
      return report;
    }
    pollfd p{fd_, POLLIN, 0};
    const timespec wait = at(std::min(left, 0.05));
    ppoll(&p, 1, &wait, nullptr);
    drain(false);
    if (interrupted()) {
      report.stopped = "interrupted while waiting for a controller";
      loop_.end("interrupted");
      return report;
    }
  }
  report.connected = true;
  // The robot's own thread at real-time priority, as a real arm's control loop runs, where the
  // machine allows it; restored when the run ends.
  int policy = SCHED_OTHER;
  sched_param previous{};
  pthread_getschedparam(pthread_self(), &policy, &previous);
  if (options_.realtime) {
    sched_param fifo{};
    fifo.sched_priority = 80;
    const int refused = pthread_setschedparam(pthread_self(), SCHED_FIFO, &fifo);
    report.scheduling = refused ? std::string("normal (SCHED_FIFO refused: ") + std::strerror(refused) + ")"
                                : std::string("SCHED_FIFO 80");
  }
  struct Restore {
    int policy;
    sched_param param;
    ~Restore() { pthread_setschedparam(pthread_self(), policy, &param); }
  } restore{policy, previous};
  const auto send = [&](const nnrobust_serve_header &h, const double *values, std::size_t count) {
    std::memcpy(out.data(), &h, header_size);
    if (count) std::memcpy(out.data() + header_size, values, sizeof(double) * count);
    sendto(fd_, out.data(), header_size + sizeof(double) * count, 0, reinterpret_cast<const sockaddr *>(&client),
           sizeof(client));
  };
  send(header(NNROBUST_SERVE_INFO, static_cast<uint64_t>(spec_.steps), period, static_cast<uint32_t>(n)), nullptr, 0);
  const double start = seconds(now()) + 0.02;  // the controller's first STATE in 20 ms
  double last_poll = start;
  std::vector<double> values(2 * static_cast<std::size_t>(n));  // STATE's q, v
  Output applied;
  applied.z = loop_.state();
  long without = 0;  // consecutive periods without a command
  while (loop_.running()) {
    const double scheduled = options_.lockstep ? seconds(now()) : start + static_cast<double>(k) * period;
    if (!options_.lockstep) {
      const timespec wake = at(scheduled);
      clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &wake, nullptr);
    }
    Eigen::Map<Vector>(values.data(), n) = loop_.measured_q();
    Eigen::Map<Vector>(values.data() + n, n) = loop_.measured_v();
    got = false;
    sent = seconds(now());
    send(header(NNROBUST_SERVE_STATE, static_cast<uint64_t>(k), loop_.time(), static_cast<uint32_t>(n)), values.data(),
         values.size());
    report.lateness.push_back(sent - scheduled);
    const double deadline = options_.lockstep ? sent + options_.wait_seconds : scheduled + period;
    bool stop = false;
    for (;;) {  // the commands until the next instant (lockstep: until this period's command)
      drain(true);
      const double left = deadline - seconds(now());
      if (left <= 0.0 || (options_.lockstep && got)) break;
      if (options_.lockstep && interrupted()) {  // a lockstep wait is long: a signal ends it at once
        stop = true;
        break;
      }
      pollfd p{fd_, POLLIN, 0};
      const timespec wait = at(options_.lockstep ? std::min(left, 0.05) : left);
      ppoll(&p, 1, &wait, nullptr);
    }
    if (stop) {
      report.stopped = "interrupted";
      loop_.end("interrupted");
      break;
    }
    if (got) {
      ++report.accepted;
      without = 0;
    } else {
      ++report.misses;
      ++without;
    }
    applied.tau = command;  // the new command, or the last one held
    applied.z = loop_.state();
    ++report.periods;
    ++k;
    if (options_.lockstep && !got) {  // a lockstep period waited --wait seconds: the controller is gone
      report.stopped = "protective stop: no command within " + std::to_string(options_.wait_seconds) +
                       " s in lockstep (the controller is gone)";
      loop_.end("interrupted");
      break;
    }
    if (without >= options_.watchdog) {
      report.stopped = "protective stop: no command for " + std::to_string(without) + " periods (the watchdog)";
      loop_.end("interrupted");
      break;
    }
    if (!loop_.advance(applied)) break;
    if (seconds(now()) - last_poll > 0.05) {
      last_poll = seconds(now());
      if (interrupted()) {
        report.stopped = "interrupted";
        loop_.end("interrupted");
        break;
      }
    }
  }
  send(header(NNROBUST_SERVE_END, static_cast<uint64_t>(report.periods), loop_.time(), static_cast<uint32_t>(n)),
       nullptr, 0);
  return report;
}

}  // namespace nnrobust
