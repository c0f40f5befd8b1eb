/* The virtual robot's protocol (`nnrobust serve`, docs/serve.md): UDP datagrams on 127.0.0.1, every
 * field in the machine's byte order (little-endian on x86-64 and ARM64), doubles IEEE 754.
 *
 * Every datagram starts with this 32-byte header. The controller (the client) sends HELLO; the
 * robot (the server) answers INFO (n joints, t = its control period, seq = the number of periods
 * it will run) and, from the next period on, sends STATE k at each control instant t_k = k T
 * (header, then q[n], v[n]: the measured joint positions and velocities). The client answers
 * COMMAND k (header with seq = k, then tau[n] [N m]) before t_{k+1}. A command that is late,
 * missing, malformed, not finite, of another period or from another sender is not applied: the
 * robot holds the last command it applied, logs the reason and, after `watchdog` periods without
 * a command, stops (its protective stop: the run ends). END (seq = periods run) closes the run.
 */
#ifndef NNROBUST_SERVE_PROTOCOL_H
#define NNROBUST_SERVE_PROTOCOL_H

#include <stdint.h>

#define NNROBUST_SERVE_MAGIC 0x53524E4Eu /* "NNRS" */
#define NNROBUST_SERVE_VERSION 1

enum nnrobust_serve_type {
  NNROBUST_SERVE_HELLO = 1,   /* client -> robot: header only */
  NNROBUST_SERVE_INFO = 2,    /* robot -> client: n, t = period [s], seq = periods */
  NNROBUST_SERVE_STATE = 3,   /* robot -> client: seq = k, t = t_k, then q[n], v[n] */
  NNROBUST_SERVE_COMMAND = 4, /* client -> robot: seq = k, then tau[n] */
  NNROBUST_SERVE_END = 5      /* robot -> client: seq = periods run */
};

typedef struct {
  uint32_t magic;   /* NNROBUST_SERVE_MAGIC */
  uint16_t version; /* NNROBUST_SERVE_VERSION */
  uint16_t type;    /* nnrobust_serve_type */
  uint64_t seq;
  double t;
  uint32_t n;
  uint32_t reserved; /* 0 */
} nnrobust_serve_header;

#endif /* NNROBUST_SERVE_PROTOCOL_H */
