// What a real arm cannot do: the twin of nnrobust/plant/limits.py (saturation and the
// Hunt-Crossley joint-limit stops, built from JointStops.twin_fields).
#pragma once

#include <algorithm>
#include <cmath>

#include "../fields.hpp"

namespace nnrobust {

// saturate: the torque the actuators apply for the command, clipped to [-limit, limit] (inf: none),
// written into `out` (no allocation once it is sized)
inline void saturate(const Vector &tau, const Vector &limit, Vector &out) { out = tau.cwiseMax(-limit).cwiseMin(limit); }

// available_torque, joint i: the effort limit, cut while driving (tau_cmd q' > 0) by the
// torque-speed envelope limit min(1, max(0, (1 - |q'| / q'_max) / (1 - knee))); knee < 0 or an
// unlimited actuator: none
inline double available_torque(double limit, double tau_cmd, double v, double speed_limit, double knee) {
  if (knee < 0.0 || !(tau_cmd * v > 0.0) || !std::isfinite(limit)) return limit;
  const double factor = (1.0 - std::abs(v) / speed_limit) / (1.0 - knee);
  return limit * std::clamp(factor, 0.0, 1.0);
}

struct JointStops {
  Vector lower, upper, stiffness;  // [rad or m], [rad or m], K [N m/rad or N/m]
  double alpha;                    // Hunt-Crossley damping [s/rad or s/m]
  Vector ring;                     // sqrt(K (M^-1)_ii) at q0 [rad/s] (0: no stop)

  explicit JointStops(const Fields &f)
      : lower(f.vector("lower")), upper(f.vector("upper")), stiffness(f.vector("stiffness")),
        alpha(f.scalar("alpha")), ring(f.vector("ring_frequencies")) {}

  // JointStops.torque, joint i: -s max(0, K delta (1 + alpha delta')) beyond a limit, s = sign
  double torque(int i, double q, double v) const {
    const double pen = std::max(q - upper[i], 0.0) + std::min(q - lower[i], 0.0);
    if (pen == 0.0) return 0.0;
    const double sg = sign(pen);
    return -sg * std::max(stiffness[i] * std::abs(pen) * (1.0 + alpha * sg * v), 0.0);
  }

  // JointStops.ringing: the highest ring frequency among the joints at their stop or that would
  // reach it within `period` at their speed (0 if none)
  double ringing(const Vector &q, const Vector &v, double period) const {
    double rate = 0.0;
    for (Eigen::Index i = 0; i < q.size(); ++i) {
      const double beyond = std::max(q[i] - upper[i], lower[i] - q[i]);
      if (beyond + std::abs(v[i]) * period > 0.0) rate = std::max(rate, ring[i]);
    }
    return rate;
  }
};

}  // namespace nnrobust
