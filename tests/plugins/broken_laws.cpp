// Laws in C++ that do what a law must not (tests/controllers/test_native_law_failures.py,
// tests/bad_inputs.py): each does it at its first compute after t = 5 ms, so that the run has
// started (a line on stderr first where a test waits for it).
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <stdexcept>

#include "nnrobust/law.hpp"

using nnrobust::Vector;

#define BROKEN_LAW(Name, ...)                                                                       \
  struct Name : nnrobust::Law {                                                                     \
    Name(const nnrobust::LawParams &, nnrobust::LawContext &) {}                                    \
    nnrobust::Output compute(double t, const Vector &q, const Vector &, const Vector &z) override { \
      if (t > 0.005) {                                                                              \
        static bool said = false;                                                                   \
        if (!said) said = std::fprintf(stderr, "%s: now\n", #Name) > 0;                             \
        __VA_ARGS__;                                                                                \
      }                                                                                             \
      return {Vector::Zero(q.size()), z, Vector(0)};                                                \
    }                                                                                               \
  };                                                                                                \
  NNROBUST_USER_LAW(Name, "", 0)

BROKEN_LAW(Exits, std::exit(0))
BROKEN_LAW(QuickExits, std::quick_exit(0))
BROKEN_LAW(UnderscoreExits, _exit(0))
BROKEN_LAW(Aborts, std::abort())
BROKEN_LAW(WritesThroughNull, *static_cast<volatile int *>(nullptr) = 1)
BROKEN_LAW(Loops, for (volatile long i = 0;; i = i + 1) {})
BROKEN_LAW(Sleeps, usleep(300))  // returns, slowly: a stop signal interrupts the run as before
BROKEN_LAW(Throws, throw std::out_of_range("index 7 of 3"))
BROKEN_LAW(WrongTorque, return {Vector::Zero(q.size() + 1), z, Vector(0)})
BROKEN_LAW(WrongState, return {Vector::Zero(q.size()), Vector::Zero(2), Vector(0)})

struct NeedsKp : nnrobust::Law {
  double Kp;
  NeedsKp(const nnrobust::LawParams &p, nnrobust::LawContext &) : Kp(p.scalar("Kp")) {}
  nnrobust::Output compute(double, const Vector &q, const Vector &, const Vector &z) override {
    return {-Kp * q, z, Vector(0)};
  }
};
NNROBUST_USER_LAW(NeedsKp, "", 0)
