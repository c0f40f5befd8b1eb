// The twin of test_kinds.py's Pulse disturbance, compiled apart (nnrobust/twin.hpp):
// tau_d(t) = level weights sin(3 t).
#include <cmath>

#include "nnrobust/twin.hpp"

namespace {

struct Pulse : nnrobust::Disturbance {
  double level;
  nnrobust::Vector weights, value;

  explicit Pulse(const nnrobust::Fields &f) : level(f.scalar("level")), weights(f.vector("weights")) {}

  const nnrobust::Vector &operator()(double t) override {
    value = level * std::sin(3.0 * t) * weights;
    return value;
  }
};

NNROBUST_DISTURBANCE("pulse", Pulse);

}  // namespace
