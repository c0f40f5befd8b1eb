// SlidingModeCompensator (nnrobust/controllers/sliding_mode.py): u_0 = -K w / max(|w|, Phi),
// w = B^T P y. Stateless.
#include <algorithm>

#include "robust_term.hpp"

namespace nnrobust {
namespace {

struct SlidingMode : RobustTerm {
  Matrix BtP;
  double gain, boundary;

  explicit SlidingMode(const Fields &f) : BtP(f.matrix("BtP")), gain(f.scalar("gain")), boundary(f.scalar("boundary")) {}

  Vector output(const Vector &, const Vector &, const Vector &y, const Vector &z, double, Vector &z_next,
                Vector &signals) const override {
    const Vector w = BtP * y;
    z_next = z;
    signals.resize(0);
    return -gain * w / std::max(w.norm(), boundary);
  }
};

}  // namespace

NNROBUST_ROBUST_TERM("sliding_mode", SlidingMode);

}  // namespace nnrobust
