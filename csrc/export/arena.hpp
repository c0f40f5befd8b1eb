// The memory an exported law's step allocates from (csrc/export/arena.cpp; docs/export.md): a
// block the law reserves (and touches) when it is created, handed out by bumping a pointer and
// taken back whole at the start of every step, so that a step never calls the system allocator.
// libnnrobust_core is linked with the malloc family and operator new/delete wrapped (GNU ld's
// --wrap, CMakeLists.txt): while a step runs on a thread, that thread's allocations come from its
// law's arena; a request the arena cannot hold falls back to the system allocator and is counted.
// A block is the step's: the arena counts the blocks it gave and that were not freed, and a step
// that ends with one still held (memory a law keeps, which the next step would hand out again) is
// an error (law_api.cpp).
#pragma once

#include <cstddef>

namespace nnrobust {

class Arena {
 public:
  explicit Arena(std::size_t bytes);
  ~Arena();
  Arena(const Arena &) = delete;
  Arena &operator=(const Arena &) = delete;

  void *take(std::size_t size, std::size_t alignment);  // nullptr when it does not fit
  bool holds(const void *p) const { return p >= begin_ && p < end_; }
  std::size_t size_of(const void *p) const;  // of a block take() gave
  void give_back() { --live_; }                // a block take() gave was freed
  void reset() { next_ = begin_, live_ = 0; }
  long live() const { return live_; }  // blocks given since the reset and not freed
  std::size_t high_water() const { return static_cast<std::size_t>(high_ - begin_); }
  long overflows = 0;  // requests that went to the system allocator during steps

 private:
  char *begin_, *end_, *next_, *high_;
  long live_ = 0;
};

// While alive, this thread's allocations come from `arena` (reset first).
class ArenaScope {
 public:
  explicit ArenaScope(Arena &arena);
  ~ArenaScope();
  ArenaScope(const ArenaScope &) = delete;
  ArenaScope &operator=(const ArenaScope &) = delete;

 private:
  Arena *previous_;
};

// Whether the allocator wrappers are linked in (false where the linker has no --wrap).
bool arena_wrapped();

}  // namespace nnrobust
