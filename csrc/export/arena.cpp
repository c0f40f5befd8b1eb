// The arena of an exported law's step (arena.hpp) and the allocator wrappers libnnrobust_core is
// linked with (CMakeLists.txt: -Wl,--wrap=malloc,... on Linux). Every call to the malloc family
// or to operator new/delete from the core's own code (the controller's parts, Eigen's and the
// standard library's inline code in them) reaches the wrappers below; the system allocator is
// __real_X.
#include "arena.hpp"

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <new>

namespace nnrobust {
namespace {
thread_local Arena *current = nullptr;
constexpr std::size_t header = 16;  // each block: its size, then the caller's bytes (16-aligned)
}  // namespace

Arena::Arena(std::size_t bytes) {
  begin_ = static_cast<char *>(std::malloc(bytes));  // before any step: the system allocator
  if (begin_ == nullptr) throw std::bad_alloc();
  std::memset(begin_, 0, bytes);  // every page touched now, not in a step
  end_ = begin_ + bytes;
  next_ = high_ = begin_;
}

Arena::~Arena() { std::free(begin_); }

void *Arena::take(std::size_t size, std::size_t alignment) {
  if (alignment < header) alignment = header;
  const auto at = reinterpret_cast<std::uintptr_t>(next_) + header;
  const std::uintptr_t aligned = (at + alignment - 1) & ~(static_cast<std::uintptr_t>(alignment) - 1);
  if (aligned + size > reinterpret_cast<std::uintptr_t>(end_) || size > static_cast<std::size_t>(end_ - begin_))
    return nullptr;
  char *block = reinterpret_cast<char *>(aligned);
  std::memcpy(block - sizeof(std::size_t), &size, sizeof(std::size_t));
  next_ = block + size;
  if (next_ > high_) high_ = next_;
  ++live_;
  return block;
}

std::size_t Arena::size_of(const void *p) const {
  std::size_t size;
  std::memcpy(&size, static_cast<const char *>(p) - sizeof(std::size_t), sizeof(std::size_t));
  return size;
}

ArenaScope::ArenaScope(Arena &arena) : previous_(current) {
  arena.reset();
  current = &arena;
}

ArenaScope::~ArenaScope() { current = previous_; }

}  // namespace nnrobust

#if defined(NNROBUST_WRAP_ALLOCATOR)
using nnrobust::current;

// The wrappers are exported: an exported law in C++ of a user's (nnrobust/export/) is linked with
// the same --wrap options against them, so its step allocates from the same arena.
#pragma GCC visibility push(default)

extern "C" {
void *__real_malloc(std::size_t);
void *__real_calloc(std::size_t, std::size_t);
void *__real_realloc(void *, std::size_t);
void __real_free(void *);
int __real_posix_memalign(void **, std::size_t, std::size_t);
void *__real_aligned_alloc(std::size_t, std::size_t);

static void *from_arena(std::size_t size, std::size_t alignment) {
  nnrobust::Arena *a = current;
  if (a == nullptr) return nullptr;
  void *p = a->take(size, alignment);
  if (p == nullptr) ++a->overflows;
  return p;
}

void *__wrap_malloc(std::size_t size) {
  void *p = from_arena(size, 16);
  return p ? p : __real_malloc(size);
}

void *__wrap_calloc(std::size_t count, std::size_t size) {
  if (current && size && count > SIZE_MAX / size) return nullptr;
  void *p = from_arena(count * size, 16);
  if (p) return std::memset(p, 0, count * size);
  return __real_calloc(count, size);
}

// Whether `p` is a block of the current arena: freeing one only counts it (the arena takes its
// blocks back whole, at the next step).
static bool taken_back(void *p) {
  if (p == nullptr || current == nullptr || !current->holds(p)) return false;
  current->give_back();
  return true;
}

void __wrap_free(void *p) {
  if (p != nullptr && !taken_back(p)) __real_free(p);
}

void *__wrap_realloc(void *old, std::size_t size) {
  if (old && current && current->holds(old)) {
    void *p = from_arena(size, 16);
    if (p == nullptr) p = __real_malloc(size);
    if (p) std::memcpy(p, old, std::min(size, current->size_of(old)));
    if (p) current->give_back();  // the old block is freed
    return p;
  }
  if (old == nullptr) return __wrap_malloc(size);
  return __real_realloc(old, size);
}

int __wrap_posix_memalign(void **out, std::size_t alignment, std::size_t size) {
  void *p = from_arena(size, alignment);
  if (p) {
    *out = p;
    return 0;
  }
  return __real_posix_memalign(out, alignment, size);
}

void *__wrap_aligned_alloc(std::size_t alignment, std::size_t size) {
  void *p = from_arena(size, alignment);
  return p ? p : __real_aligned_alloc(alignment, size);
}

// operator new and delete (Itanium names), plain and aligned
void *__real__Znwm(std::size_t);
void *__real__Znam(std::size_t);
void *__real__ZnwmSt11align_val_t(std::size_t, std::align_val_t);
void *__real__ZnamSt11align_val_t(std::size_t, std::align_val_t);
void __real__ZdlPv(void *);
void __real__ZdaPv(void *);
void __real__ZdlPvm(void *, std::size_t);
void __real__ZdaPvm(void *, std::size_t);
void __real__ZdlPvSt11align_val_t(void *, std::align_val_t);
void __real__ZdaPvSt11align_val_t(void *, std::align_val_t);
void __real__ZdlPvmSt11align_val_t(void *, std::size_t, std::align_val_t);
void __real__ZdaPvmSt11align_val_t(void *, std::size_t, std::align_val_t);

void *__wrap__Znwm(std::size_t size) {
  void *p = from_arena(size, 16);
  return p ? p : __real__Znwm(size);
}
void *__wrap__Znam(std::size_t size) {
  void *p = from_arena(size, 16);
  return p ? p : __real__Znam(size);
}
void *__wrap__ZnwmSt11align_val_t(std::size_t size, std::align_val_t alignment) {
  void *p = from_arena(size, static_cast<std::size_t>(alignment));
  return p ? p : __real__ZnwmSt11align_val_t(size, alignment);
}
void *__wrap__ZnamSt11align_val_t(std::size_t size, std::align_val_t alignment) {
  void *p = from_arena(size, static_cast<std::size_t>(alignment));
  return p ? p : __real__ZnamSt11align_val_t(size, alignment);
}
void __wrap__ZdlPv(void *p) {
  if (p != nullptr && !taken_back(p)) __real__ZdlPv(p);
}
void __wrap__ZdaPv(void *p) {
  if (p != nullptr && !taken_back(p)) __real__ZdaPv(p);
}
void __wrap__ZdlPvm(void *p, std::size_t n) {
  if (p != nullptr && !taken_back(p)) __real__ZdlPvm(p, n);
}
void __wrap__ZdaPvm(void *p, std::size_t n) {
  if (p != nullptr && !taken_back(p)) __real__ZdaPvm(p, n);
}
void __wrap__ZdlPvSt11align_val_t(void *p, std::align_val_t a) {
  if (p != nullptr && !taken_back(p)) __real__ZdlPvSt11align_val_t(p, a);
}
void __wrap__ZdaPvSt11align_val_t(void *p, std::align_val_t a) {
  if (p != nullptr && !taken_back(p)) __real__ZdaPvSt11align_val_t(p, a);
}
void __wrap__ZdlPvmSt11align_val_t(void *p, std::size_t n, std::align_val_t a) {
  if (p != nullptr && !taken_back(p)) __real__ZdlPvmSt11align_val_t(p, n, a);
}
void __wrap__ZdaPvmSt11align_val_t(void *p, std::size_t n, std::align_val_t a) {
  if (p != nullptr && !taken_back(p)) __real__ZdaPvmSt11align_val_t(p, n, a);
}
}  // extern "C"
#pragma GCC visibility pop

bool nnrobust::arena_wrapped() { return true; }
#else
bool nnrobust::arena_wrapped() { return false; }
#endif
