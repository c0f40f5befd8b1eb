// What the controller measures: the twin of nnrobust/plant/sensing.py's Sensor, built from its
// twin_fields and the standard normal draws of its seed (Sensor.twin_draws: column k holds step
// k's, the same draws in the same order as Sensor.measure's).
#pragma once

#include <cmath>

#include "../fields.hpp"

namespace nnrobust {

struct Sensor {
  Vector position_noise, velocity_noise, resolution;  // standard deviations, encoder count
  Matrix noise_q, noise_v;                            // n x steps draws (n x 0: an ideal sensor)

  explicit Sensor(const Fields &f)
      : position_noise(f.vector("position_noise")), velocity_noise(f.vector("velocity_noise")),
        resolution(f.vector("resolution")), noise_q(f.matrix("noise_q")), noise_v(f.matrix("noise_v")) {}

  // Sensor.measure at step k: q_m = Q(q + n_q), q'_m = q' + n_v (Q rounds to the encoder count)
  void measure(long k, const Vector &q, const Vector &v, Vector &qm, Vector &vm) const {
    qm = q;
    vm = v;
    if (noise_q.cols() == 0) return;
    for (Eigen::Index i = 0; i < q.size(); ++i) {
      qm[i] = q[i] + position_noise[i] * noise_q(i, k);
      vm[i] = v[i] + velocity_noise[i] * noise_v(i, k);
      const double r = resolution[i];
      if (r > 0) qm[i] = std::nearbyint(qm[i] / r) * r;
    }
  }
};

}  // namespace nnrobust
