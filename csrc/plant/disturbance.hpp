// The external disturbance tau_d(t) of eq. (7) on the C++ side, the twins of
// nnrobust/plant/disturbance.py: each is a class registered under its Python class's `twin` name
// (the name of its plant.disturbance kind) and built from the fields its `twin_fields` list.
#pragma once

#include <cmath>
#include <limits>
#include <memory>

#include "../fields.hpp"
#include "../registry.hpp"

namespace nnrobust {

// tau_d(t), one torque per joint (Disturbance.__call__); the plant asks for it at each RK4 stage
struct Disturbance {
  virtual ~Disturbance() = default;
  virtual const Vector &operator()(double t) = 0;
};

using DisturbanceRegistry = Registry<Disturbance, const Fields &>;

struct SinusoidalDisturbance final : Disturbance {
  Matrix amplitude, phase;  // A, phi: n x K [N m], [rad]
  Vector omega;             // K [rad/s]

  explicit SinusoidalDisturbance(const Fields &f)
      : amplitude(f.matrix("amplitude")), phase(f.matrix("phase")), omega(f.vector("omega")) {
    if (phase.rows() != amplitude.rows() || phase.cols() != amplitude.cols() || omega.size() != amplitude.cols())
      throw std::invalid_argument(f.owner + ": amplitude, omega and phase must be n x K, K and n x K");
  }

  // SinusoidalDisturbance.__call__: tau_d,i(t) = sum_k A_ik sin(omega_k t + phi_ik), kept for the
  // last t asked (RK4 asks twice at t + h / 2, and a step's end is the next step's start)
  const Vector &operator()(double t) override {
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

// Registers `Class` (constructed as Class(const Fields &)) under `name`.
#define NNROBUST_DISTURBANCE(name, Class)                                                              \
  static const bool nnrobust_registered_##Class = ::nnrobust::DisturbanceRegistry::add(               \
      name, [](const ::nnrobust::Fields &f) -> std::unique_ptr<::nnrobust::Disturbance> {              \
        return std::make_unique<Class>(f);                                                             \
      })

// a twin compiled apart hands its disturbances over (registry.hpp)
NNROBUST_SHARE_REGISTRY(::nnrobust::DisturbanceRegistry, nnrobust_twin_disturbances)
