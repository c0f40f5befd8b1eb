// The twin of test_kinds.py's FigureEight path, compiled apart (nnrobust/twin.hpp):
// p_d(t) = center + axis_a cos(w t) + stretch axis_b sin(2 w t).
#include <cmath>

#include "nnrobust/twin.hpp"

namespace {

struct FigureEight : nnrobust::Path {
  nnrobust::Vector center, axis_a, axis_b;
  double omega, stretch;

  explicit FigureEight(const nnrobust::Fields &f)
      : center(f.vector("center")), axis_a(f.vector("axis_a")), axis_b(f.vector("axis_b")),
        omega(f.scalar("omega")), stretch(f.scalar("stretch")) {}

  void at(double t, nnrobust::Vector &p, nnrobust::Vector &dp, nnrobust::Vector &ddp) const override {
    const double w = omega, c = std::cos(w * t), s2 = std::sin(2.0 * w * t), c2 = std::cos(2.0 * w * t);
    p = center + axis_a * c + stretch * axis_b * s2;
    dp = -w * std::sin(w * t) * axis_a + 2.0 * w * stretch * c2 * axis_b;
    ddp = -w * w * c * axis_a - 4.0 * w * w * stretch * s2 * axis_b;
  }
};

NNROBUST_PATH("figure-eight", FigureEight);

}  // namespace
