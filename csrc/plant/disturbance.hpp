// The external disturbance tau_d(t) of eq. (7): the twin of nnrobust/plant/disturbance.py's
// SinusoidalDisturbance, built from its twin_fields.
#pragma once

#include <cmath>
#include <limits>

#include "../fields.hpp"

namespace nnrobust {

struct SinusoidalDisturbance {
  Matrix amplitude, phase;  // A, phi: n x K [N m], [rad]
  Vector omega;             // K [rad/s]

  explicit SinusoidalDisturbance(const Fields &f)
      : amplitude(f.matrix("amplitude")), phase(f.matrix("phase")), omega(f.vector("omega")) {
    if (phase.rows() != amplitude.rows() || phase.cols() != amplitude.cols() || omega.size() != amplitude.cols())
      throw std::invalid_argument(f.owner + ": amplitude, omega and phase must be n x K, K and n x K");
  }

  // SinusoidalDisturbance.__call__: tau_d,i(t) = sum_k A_ik sin(omega_k t + phi_ik), kept for the
  // last t asked (RK4 asks twice at t + h / 2, and a step's end is the next step's start)
  const Vector &operator()(double t) {
    if (t != t_ || value_.size() != amplitude.rows()) {
      value_.resize(amplitude.rows());
      for (Eigen::Index i = 0; i < value_.size(); ++i) {
        double d = 0.0;
        for (Eigen::Index k = 0; k < omega.size(); ++k) d += amplitude(i, k) * std::sin(omega[k] * t + phase(i, k));
        value_[i] = d;
      }
      t_ = t;
    }
    return value_;
  }

 private:
  Vector value_;
  double t_ = std::numeric_limits<double>::quiet_NaN();
};

}  // namespace nnrobust
