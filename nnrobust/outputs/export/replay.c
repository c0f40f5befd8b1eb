/* replay.c: the example program of an exported law (`nnrobust export`, docs/export.md).
 *
 * It replays measured states through the law: each line of standard input is
 *     t q_1 .. q_n v_1 .. v_n
 * (time [s], measured joint positions and velocities) and each line of standard output the
 * commanded torques tau_1 .. tau_n, printed with 17 significant digits (exact for float64).
 * With an argument, the law is read from that law.description file instead of the one compiled
 * into libnnrobust_law.
 *
 * On a robot the same three calls sit in the real-time loop: nnrobust_law_create() once, before
 * the loop starts (it allocates); nnrobust_law_step() once per control period, from the
 * controller's update (a ros2_control controller's update(), a libfranka torque callback) with
 * the state the robot just measured; nnrobust_law_destroy() after the loop.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "nnrobust_law.h"

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

int main(int argc, char **argv) {
  nnrobust_law *law;
  if (argc > 1) {
    char *text = read_file(argv[1]);
    if (!text) {
      fprintf(stderr, "replay: cannot read %s\n", argv[1]);
      return 2;
    }
    law = nnrobust_law_create_from(text);
    free(text);
  } else {
    law = nnrobust_law_create();
  }
  if (!law) {
    fprintf(stderr, "replay: %s\n", nnrobust_law_last_error());
    return 2;
  }
  const int n = nnrobust_law_dof(law);
  double *q = malloc(sizeof(double) * (size_t)n), *v = malloc(sizeof(double) * (size_t)n);
  double *tau = malloc(sizeof(double) * (size_t)n);
  double t;
  long line = 0;
  int status = 0;
  while (scanf("%lf", &t) == 1) {
    ++line;
    for (int i = 0; i < n; ++i)
      if (scanf("%lf", &q[i]) != 1) status = 2;
    for (int i = 0; i < n; ++i)
      if (scanf("%lf", &v[i]) != 1) status = 2;
    if (status) {
      fprintf(stderr, "replay: line %ld needs t and %d numbers\n", line, 2 * n);
      break;
    }
    const int step = nnrobust_law_step(law, t, q, v, tau);
    if (step < 0) {
      fprintf(stderr, "replay: line %ld: %s\n", line, nnrobust_law_last_error());
      status = 1;
      break;
    }
    for (int i = 0; i < n; ++i) printf(i ? " %.17g" : "%.17g", tau[i]);
    printf("\n");
  }
  free(q);
  free(v);
  free(tau);
  nnrobust_law_destroy(law);
  return status;
}
