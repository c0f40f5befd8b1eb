// EllipseTrajectory (nnrobust/trajectories/ellipse.py), eq. (18):
// p_d(t) = center + axis_a cos(w t + phi) + axis_b sin(w t + phi).
#include <cmath>

#include "trajectory.hpp"

namespace nnrobust {
namespace {

struct Ellipse : Path {
  Vector center, axis_a, axis_b;
  double omega, phase;

  explicit Ellipse(const Fields &f)
      : center(f.vector("center")), axis_a(f.vector("axis_a")), axis_b(f.vector("axis_b")),
        omega(f.scalar("omega")), phase(f.scalar("phase")) {}

  void at(double t, Vector &p, Vector &dp, Vector &ddp) const override {
    const double ph = omega * t + phase, cw = std::cos(ph), sw = std::sin(ph);
    p = center + axis_a * cw + axis_b * sw;
    dp = omega * (-axis_a * sw + axis_b * cw);
    ddp = -(omega * omega) * (axis_a * cw + axis_b * sw);
  }
};

}  // namespace

NNROBUST_PATH("ellipse", Ellipse);

}  // namespace nnrobust
