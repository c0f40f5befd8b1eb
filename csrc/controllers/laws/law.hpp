// The registered control laws on the C++ side (the twins of nnrobust/controllers/laws/): each law
// is one file here that registers itself by name with NNROBUST_LAW, reads its numbers by name
// from the fields its Python twin declares (Law.twin_fields; no defaults here: a missing field
// is an error that names it), and uses the shared parts of the controller (the desired motion,
// the damped pseudo-inverse, the criteria) through LawContext.
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "../../controllers.hpp"
#include "../../fields.hpp"
#include "../../registry.hpp"

namespace nnrobust {

// A registered law's fields, as LoopSpec.law_params carries them (Law.twin_values).
using LawParams = Fields;

// The task-space reference at a control instant (TaskSpaceController.compute's first lines):
// the nominal model's task state, the task error e = x - x_d and e' = J q' - x_d', x_d', x_d''.
struct TaskReference {
  TaskState ts;
  Vector e, de, dxd, ddxd;
};

// What a law is built with: the loop's spec, the controller's nominal model and the shared parts.
struct LawContext {
  const LoopSpec &spec;
  Nominal &nominal;
  Controller &shared;
};

struct Law {
  virtual ~Law() = default;
  // the torque, the signals (in the Python law's signal_names order) and the next state at t
  virtual Output compute(double t, const Vector &q, const Vector &v, const Vector &z) = 0;
  // The learning environment's gains mode (nnrobust/controllers/laws/policy.py): from the next
  // compute on, the law's position and velocity gains are its own times `position` and
  // `velocity`. False for a law without such a pair of gains.
  virtual bool scale_gains(double position, double velocity) {
    (void)position;
    (void)velocity;
    return false;
  }
};

// The laws by the name their Python twin declares (Law.twin, or the controller class's twin)
using LawRegistry = Registry<Law, const LawParams &, LawContext &>;

}  // namespace nnrobust

// Registers `Class` (constructed as Class(const LawParams &, LawContext &)) under `name`.
#define NNROBUST_LAW(name, Class)                                                                            \
  static const bool nnrobust_registered_##Class = ::nnrobust::LawRegistry::add(                                      \
      name, [](const ::nnrobust::LawParams &p, ::nnrobust::LawContext &c) -> std::unique_ptr<::nnrobust::Law> { \
        return std::make_unique<Class>(p, c);                                                                \
      })

// A user's law compiled apart (docs/extending.md#a-law-in-c): one .cpp file that defines `Class`
// (a Law, constructed as Class(const LawParams &, LawContext &)) and names it here, at global
// scope, with its signals (comma-separated names, "" for none) and its state size (an expression
// of n, the joint count; the state starts at zero). nnrobust compiles the file on first use and
// calls these three functions of it.
#define NNROBUST_USER_LAW(Class, signals, state_size)                                                     \
  extern "C" NNROBUST_API ::nnrobust::Law *nnrobust_law_factory_##Class(const ::nnrobust::LawParams &p, \
                                                                          ::nnrobust::LawContext &c) {   \
    return new Class(p, c);                                                                             \
  }                                                                                                      \
  extern "C" NNROBUST_API const char *nnrobust_law_signals_##Class(void) { return signals; }            \
  extern "C" NNROBUST_API int nnrobust_law_state_##Class(int n) {                                       \
    (void)n;                                                                                             \
    return (state_size);                                                                                 \
  }

// Optional, after NNROBUST_USER_LAW: the parameters `nnrobust tune` searches for `Class`, as
// "name=low:high[:unit]" entries separated by commas, each searched log-uniformly between
// 0 < low < high (a Python law's search_space; docs/extending.md#tuning-it).
#define NNROBUST_USER_LAW_SPACE(Class, space) \
  extern "C" NNROBUST_API const char *nnrobust_law_space_##Class(void) { return space; }

// a twin compiled apart hands its laws over (registry.hpp)
NNROBUST_SHARE_REGISTRY(::nnrobust::LawRegistry, nnrobust_twin_laws)
