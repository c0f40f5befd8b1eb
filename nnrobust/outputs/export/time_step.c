/* The exported law's step, timed, with its heap allocations counted: an example shipped with every
 * export (bin/time_step; nnrobust.export.time_steps, benchmarks/export_step.py, the study's
 * realtime stage).
 *
 *     time_step INPUTS REPEATS
 *
 * INPUTS is a binary file of rows (t, q_1..q_n, v_1..v_n) in float64, a compiled run's measured
 * states. The law steps through them REPEATS times (reset between passes); each step is timed
 * with CLOCK_MONOTONIC, and every malloc, calloc, realloc and aligned allocation the process makes
 * during the steps (never during create) is counted by the wrappers below, which replace glibc's
 * for the whole process (libnnrobust_core and Pinocchio included). Prints one line: steps,
 * allocations, then the step times in nanoseconds, sorted.
 */
#define _GNU_SOURCE
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "nnrobust_law.h"

extern void *__libc_malloc(size_t);
extern void *__libc_calloc(size_t, size_t);
extern void *__libc_realloc(void *, size_t);
extern void *__libc_memalign(size_t, size_t);
extern void __libc_free(void *);

static volatile int counting = 0;
static long allocations = 0;

void *malloc(size_t size) {
  if (counting) ++allocations;
  return __libc_malloc(size);
}
void *calloc(size_t count, size_t size) {
  if (counting) ++allocations;
  return __libc_calloc(count, size);
}
void *realloc(void *p, size_t size) {
  if (counting) ++allocations;
  return __libc_realloc(p, size);
}
void *memalign(size_t alignment, size_t size) {
  if (counting) ++allocations;
  return __libc_memalign(alignment, size);
}
void *aligned_alloc(size_t alignment, size_t size) { return memalign(alignment, size); }
int posix_memalign(void **out, size_t alignment, size_t size) {
  *out = memalign(alignment, size);
  return *out ? 0 : 12;
}
void free(void *p) { __libc_free(p); }

static int by_value(const void *a, const void *b) {
  const long x = *(const long *)a, y = *(const long *)b;
  return (x > y) - (x < y);
}

int main(int argc, char **argv) {
  if (argc != 3) {
    fprintf(stderr, "usage: time_step INPUTS REPEATS\n");
    return 2;
  }
  nnrobust_law *law = nnrobust_law_create();
  if (!law) {
    fprintf(stderr, "time_step: %s\n", nnrobust_law_last_error());
    return 2;
  }
  const int n = nnrobust_law_dof(law);
  FILE *f = fopen(argv[1], "rb");
  if (!f) return 2;
  fseek(f, 0, SEEK_END);
  const long rows = ftell(f) / (long)(sizeof(double) * (size_t)(1 + 2 * n));
  fseek(f, 0, SEEK_SET);
  double *data = malloc(sizeof(double) * (size_t)(rows * (1 + 2 * n)));
  if (fread(data, sizeof(double) * (size_t)(1 + 2 * n), (size_t)rows, f) != (size_t)rows) return 2;
  fclose(f);
  const int repeats = atoi(argv[2]);
  long *times = malloc(sizeof(long) * (size_t)(rows * repeats));
  double *tau = malloc(sizeof(double) * (size_t)n);
  long k = 0;
  for (int r = 0; r < repeats; ++r) {
    nnrobust_law_reset(law);
    for (long i = 0; i < rows; ++i) {
      const double *row = data + i * (1 + 2 * n);
      struct timespec a, b;
      clock_gettime(CLOCK_MONOTONIC, &a);
      counting = 1;
      const int status = nnrobust_law_step(law, row[0], row + 1, row + 1 + n, tau);
      counting = 0;
      clock_gettime(CLOCK_MONOTONIC, &b);
      if (status < 0) {
        fprintf(stderr, "time_step: %s\n", nnrobust_law_last_error());
        return 1;
      }
      times[k++] = (b.tv_sec - a.tv_sec) * 1000000000L + (b.tv_nsec - a.tv_nsec);
    }
  }
  qsort(times, (size_t)k, sizeof(long), by_value);
  printf("%ld %ld", k, allocations);
  for (long i = 0; i < k; ++i) printf(" %ld", times[i]);
  printf("\n");
  nnrobust_law_destroy(law);
  return 0;
}
