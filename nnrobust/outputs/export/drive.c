/* drive.c: the exported law as the controller of a virtual robot (`nnrobust serve`, docs/serve.md).
 *
 *     drive PORT [HOST [DESCRIPTION]]
 *
 * It says HELLO to the robot at HOST:PORT (default 127.0.0.1), then at each STATE it receives
 * steps the law (nnrobust_law_step with the state's t, q and v) and sends the COMMAND of that
 * period, until the robot's END. With DESCRIPTION, the law is read from that law.description
 * file instead of the one compiled into libnnrobust_law. The protocol is protocol.h's.
 */
#define _GNU_SOURCE
#include <arpa/inet.h>
#include <netinet/in.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <time.h>
#include <unistd.h>

#include "nnrobust_law.h"
#include "protocol.h"

static char *read_file(const char *path) {
  FILE *f = fopen(path, "rb");
  if (!f) return NULL;
  fseek(f, 0, SEEK_END);
  long size = ftell(f);
  fseek(f, 0, SEEK_SET);
  char *text = malloc((size_t)size + 1);
  if (text && fread(text, 1, (size_t)size, f) != (size_t)size) {
    free(text);
    text = NULL;
  }
  if (text) text[size] = '\0';
  fclose(f);
  return text;
}

static double now(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static nnrobust_serve_header make_header(uint16_t type, uint64_t seq, uint32_t n) {
  nnrobust_serve_header h;
  memset(&h, 0, sizeof h);
  h.magic = NNROBUST_SERVE_MAGIC;
  h.version = NNROBUST_SERVE_VERSION;
  h.type = type;
  h.seq = seq;
  h.n = n;
  return h;
}

int main(int argc, char **argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: drive PORT [HOST [DESCRIPTION]]\n");
    return 2;
  }
  const int port = atoi(argv[1]);
  const char *host = argc > 2 ? argv[2] : "127.0.0.1";
  nnrobust_law *law;
  if (argc > 3) {
    char *text = read_file(argv[3]);
    if (!text) {
      fprintf(stderr, "drive: cannot read %s\n", argv[3]);
      return 2;
    }
    law = nnrobust_law_create_from(text);
    free(text);
  } else {
    law = nnrobust_law_create();
  }
  if (!law) {
    fprintf(stderr, "drive: %s\n", nnrobust_law_last_error());
    return 2;
  }
  const int n = nnrobust_law_dof(law);
  const int fd = socket(AF_INET, SOCK_DGRAM, 0);
  struct sockaddr_in robot;
  memset(&robot, 0, sizeof robot);
  robot.sin_family = AF_INET;
  robot.sin_port = htons((uint16_t)port);
  if (fd < 0 || inet_pton(AF_INET, host, &robot.sin_addr) != 1 ||
      connect(fd, (struct sockaddr *)&robot, sizeof robot) != 0) {
    fprintf(stderr, "drive: cannot reach %s:%d\n", host, port);
    return 2;
  }
  struct timeval half = {0, 500000};
  setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &half, sizeof half);
  size_t size = sizeof(nnrobust_serve_header) + 2 * sizeof(double) * (size_t)n;
  unsigned char *in = malloc(size + 64), *out = malloc(sizeof(nnrobust_serve_header) + sizeof(double) * (size_t)n);
  double *q = malloc(sizeof(double) * (size_t)n), *v = malloc(sizeof(double) * (size_t)n);
  double *tau = malloc(sizeof(double) * (size_t)n);
  nnrobust_serve_header h = make_header(NNROBUST_SERVE_HELLO, 0, (uint32_t)n);
  int ready = 0;
  for (int attempt = 0; attempt < 20 && !ready; ++attempt) {  /* HELLO until INFO, 10 s at most */
    send(fd, &h, sizeof h, 0);
    const ssize_t got = recv(fd, in, size + 64, 0);
    if (got >= (ssize_t)sizeof h) {
      memcpy(&h, in, sizeof h);
      ready = h.magic == NNROBUST_SERVE_MAGIC && h.type == NNROBUST_SERVE_INFO;
    }
  }
  if (!ready) {
    fprintf(stderr, "drive: no robot answered at %s:%d\n", host, port);
    return 1;
  }
  if (h.n != (uint32_t)n) {
    fprintf(stderr, "drive: the robot has %u joints, the law %d\n", h.n, n);
    return 2;
  }
  struct timeval patience = {5, 0};
  setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &patience, sizeof patience);
  long periods = 0;
  double slowest = 0.0;
  int status = 0;
  for (;;) {
    const ssize_t got = recv(fd, in, size + 64, 0);
    if (got < 0) {
      fprintf(stderr, "drive: no STATE for 5 s\n");
      status = 1;
      break;
    }
    if (got < (ssize_t)sizeof h) continue;
    memcpy(&h, in, sizeof h);
    if (h.magic != NNROBUST_SERVE_MAGIC) continue;
    if (h.type == NNROBUST_SERVE_END) break;
    if (h.type != NNROBUST_SERVE_STATE || (size_t)got != size) continue;
    memcpy(q, in + sizeof h, sizeof(double) * (size_t)n);
    memcpy(v, in + sizeof h + sizeof(double) * (size_t)n, sizeof(double) * (size_t)n);
    const double start = now();
    const int step = nnrobust_law_step(law, h.t, q, v, tau);
    const double took = now() - start;
    if (took > slowest) slowest = took;
    if (step != 0) {  /* no command: the robot holds its last one, then stops (its watchdog) */
      if (step < 0) fprintf(stderr, "drive: %s\n", nnrobust_law_last_error());
      continue;
    }
    nnrobust_serve_header c = make_header(NNROBUST_SERVE_COMMAND, h.seq, (uint32_t)n);
    memcpy(out, &c, sizeof c);
    memcpy(out + sizeof c, tau, sizeof(double) * (size_t)n);
    send(fd, out, sizeof c + sizeof(double) * (size_t)n, 0);
    ++periods;
  }
  fprintf(stderr, "drive: %ld periods commanded; slowest law step %.1f us\n", periods, slowest * 1e6);
  free(in);
  free(out);
  free(q);
  free(v);
  free(tau);
  close(fd);
  nnrobust_law_destroy(law);
  return status;
}
