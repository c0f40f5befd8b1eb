// Joint friction F(q'): the twin of nnrobust/plant/friction.py, built from Friction.twin_fields
// (the true robot's and the controller's F-hat).
#pragma once

#include <algorithm>

#include "../fields.hpp"

namespace nnrobust {

struct Friction {
  Vector viscous, coulomb;  // F_d [N m s/rad], F_c [N m]
  Vector stiction;          // F_s, the most a joint at rest is held by [N m] (Friction.static)
  double smoothing;         // v_s [rad/s]: sgn replaced by sat(q' / v_s) (0: the exact sgn)

  explicit Friction(const Fields &f)
      : viscous(f.vector("viscous")), coulomb(f.vector("coulomb")), stiction(f.vector("static")),
        smoothing(f.scalar("smoothing")) {}

  // Friction.torque, joint i: F_d q' + F_c sgn(q') (sgn(0) = 0), or sat(q' / v_s) for the sign
  double torque(int i, double v) const {
    const double sg = smoothing <= 0 ? sign(v) : std::clamp(v / smoothing, -1.0, 1.0);
    return viscous[i] * v + coulomb[i] * sg;
  }
  // Plant.sticky: dry friction that holds joint i at rest (integrated as stick-slip)
  bool sticky(int i) const { return stiction[i] > 0 && smoothing <= 0; }
};

}  // namespace nnrobust
