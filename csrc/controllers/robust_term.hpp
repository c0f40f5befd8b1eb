// The robust terms u_0 of eq. (9) on the C++ side, the twins of the RobustTerm classes of
// nnrobust/controllers/ (nn_compensator.py, sliding_mode.py): each is one file here, registered
// under its Python class's `twin` name and built from the fields its `twin_fields` list.
#pragma once

#include <memory>

#include "../fields.hpp"
#include "../registry.hpp"

namespace nnrobust {

struct RobustTerm {
  virtual ~RobustTerm() = default;
  // RobustTerm.output: u_0 at the measured (q, q') and y = [e, e'] with the state z; the state
  // after `period` into z_next and the signals (its Python twin's signal_names order) into signals
  virtual Vector output(const Vector &q, const Vector &v, const Vector &y, const Vector &z, double period,
                        Vector &z_next, Vector &signals) const = 0;
};

using RobustTermRegistry = Registry<RobustTerm, const Fields &>;

}  // namespace nnrobust

// Registers `Class` (constructed as Class(const Fields &)) under `name`.
#define NNROBUST_ROBUST_TERM(name, Class)                                                              \
  static const bool nnrobust_registered_##Class = ::nnrobust::RobustTermRegistry::add(                \
      name, [](const ::nnrobust::Fields &f) -> std::unique_ptr<::nnrobust::RobustTerm> {               \
        return std::make_unique<Class>(f);                                                             \
      })

// a twin compiled apart hands its robust terms over (registry.hpp)
NNROBUST_SHARE_REGISTRY(::nnrobust::RobustTermRegistry, nnrobust_twin_robust_terms)
