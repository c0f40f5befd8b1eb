// The twin of test_kinds.py's SmoothSign robust term, compiled apart (nnrobust/twin.hpp):
// u_0 = -gain tanh(w / boundary) entry by entry, w = B^T P y. Stateless.
#include "nnrobust/twin.hpp"

namespace {

struct SmoothSign : nnrobust::RobustTerm {
  nnrobust::Matrix BtP;
  double gain, boundary;

  explicit SmoothSign(const nnrobust::Fields &f)
      : BtP(f.matrix("BtP")), gain(f.scalar("gain")), boundary(f.scalar("boundary")) {}

  nnrobust::Vector output(const nnrobust::Vector &, const nnrobust::Vector &, const nnrobust::Vector &y,
                          const nnrobust::Vector &z, double, nnrobust::Vector &z_next,
                          nnrobust::Vector &signals) const override {
    z_next = z;
    signals.resize(0);
    return -gain * (BtP * y / boundary).array().tanh().matrix();
  }
};

NNROBUST_ROBUST_TERM("smooth-sign", SmoothSign);

}  // namespace
