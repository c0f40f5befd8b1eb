// PiecewisePolynomialPath (nnrobust/trajectories/piecewise.py): breaks b_0..b_P; row p (degree + 1) + j
// of the stacked coefficients (P (degree + 1) x m) multiplies (t - b_p)^j; at rest before b_0 and
// held at its end after b_P. Evaluated by Horner's rule.
#include <algorithm>

#include "trajectory.hpp"

namespace nnrobust {
namespace {

struct Piecewise : Path {
  Vector breaks;
  Matrix coefficients;
  int pieces, order;

  explicit Piecewise(const Fields &f)
      : breaks(f.vector("breaks")), coefficients(f.matrix("stacked_coefficients")),
        pieces(static_cast<int>(breaks.size()) - 1),
        order(pieces > 0 ? static_cast<int>(coefficients.rows()) / pieces : 0) {}

  void at(double t, Vector &p, Vector &dp, Vector &ddp) const override {
    const Vector &b = breaks;
    int piece = 0;
    double h = 0.0;
    bool moving = false;
    if (t >= b[pieces]) {
      piece = pieces - 1;
      h = b[pieces] - b[piece];
    } else if (t > b[0]) {
      piece = static_cast<int>(std::upper_bound(b.data(), b.data() + b.size(), t) - b.data()) - 1;
      h = t - b[piece];
      moving = true;
    }
    const int m = static_cast<int>(coefficients.cols());
    p = coefficients.row(piece * order + order - 1).transpose();
    dp = Vector::Zero(m);
    ddp = Vector::Zero(m);
    for (int j = order - 2; j >= 0; --j) {
      ddp = ddp * h + 2 * dp;
      dp = dp * h + p;
      p = p * h + coefficients.row(piece * order + j).transpose();
    }
    if (!moving) {
      dp.setZero();
      ddp.setZero();
    }
  }
};

}  // namespace

NNROBUST_PATH("piecewise", Piecewise);

}  // namespace nnrobust
