// A counter of the calls a thread makes to the system allocator, for the compiled loop's profile
// (benchmarks/loop_profile.py; tests/run/test_loop_profile.py). Preloaded (LD_PRELOAD), it stands
// in front of glibc's malloc family; the loop reads nnrobust_allocations() (a weak symbol of
// nnrobust._loop) at each part of a step when LoopSpec.profile is set. Built with the package
// (CMakeLists.txt) as nnrobust/libnnrobust_allocation_counter.so. Linux and glibc only: the
// __libc_* entry points are glibc's.
#include <cerrno>
#include <cstddef>

extern "C" {

extern void *__libc_malloc(size_t size);
extern void *__libc_calloc(size_t count, size_t size);
extern void *__libc_realloc(void *ptr, size_t size);
extern void *__libc_memalign(size_t alignment, size_t size);
extern void __libc_free(void *ptr);

static __thread long calls __attribute__((tls_model("initial-exec")));

long nnrobust_allocations(void) { return calls; }

void *malloc(size_t size) {
  ++calls;
  return __libc_malloc(size);
}

void *calloc(size_t count, size_t size) {
  ++calls;
  return __libc_calloc(count, size);
}

void *realloc(void *ptr, size_t size) {
  ++calls;
  return __libc_realloc(ptr, size);
}

void *memalign(size_t alignment, size_t size) {
  ++calls;
  return __libc_memalign(alignment, size);
}

void *aligned_alloc(size_t alignment, size_t size) {
  ++calls;
  return __libc_memalign(alignment, size);
}

int posix_memalign(void **out, size_t alignment, size_t size) {
  ++calls;
  if (alignment % sizeof(void *) != 0 || (alignment & (alignment - 1)) != 0) return EINVAL;
  void *ptr = __libc_memalign(alignment, size);
  if (ptr == nullptr && size != 0) return ENOMEM;
  *out = ptr;
  return 0;
}

void free(void *ptr) { __libc_free(ptr); }

}  // extern "C"
