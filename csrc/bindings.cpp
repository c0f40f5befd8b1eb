// nnrobust._loop: the one binding module of the compiled backend (docs/compiled.md).
#include <nanobind/eigen/dense.h>
#include <nanobind/nanobind.h>
#include <nanobind/stl/map.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

#include <Python.h>

#include <chrono>
#include <exception>
#include <stdexcept>
#include <string>

#include "closed_loop.hpp"
#include "model.hpp"

namespace nb = nanobind;
using nnrobust::LoadedModel;
using nnrobust::LoopSpec;
using nnrobust::ModelSpec;
using nnrobust::LoopTrace;

namespace {

// Polled by the loop with the GIL released: a pending Ctrl-C or SIGTERM stops the run. The GIL
// is taken at most every 50 ms per thread: in a Dask worker, whose event loop holds the GIL
// between its own calls, taking it every 256 steps (a few hundred times per second) cost a 20 s
// paper-ellipse run about 14 % of its time (benchmarks/sweep_throughput.py).
bool python_signal_pending() {
  using Clock = std::chrono::steady_clock;
  thread_local Clock::time_point last{};
  const Clock::time_point now = Clock::now();
  if (now - last < std::chrono::milliseconds(50)) return false;
  last = now;
  nb::gil_scoped_acquire gil;
  if (PyErr_CheckSignals() != 0) {
    PyErr_Clear();
    return true;
  }
  return false;
}

LoopTrace run(LoadedModel &plant, const LoopSpec &spec, LoadedModel *nominal) {
  if (spec.nominal == "pinocchio" && nominal == nullptr)
    throw std::invalid_argument("the nominal model 'pinocchio' needs its model");
  nb::gil_scoped_release released;
  return nnrobust::run_loop(plant, nominal, spec, &python_signal_pending);
}

// The hybrid loop: the compiled plant calling a Python control law once per period, the GIL held
// for the whole run (the law runs in this thread). law(t, q, v, z) -> (tau, z_next), or None to
// stop the run as interrupted; an exception it raises stops the run and is raised again here.
LoopTrace hybrid(LoadedModel &plant, const LoopSpec &spec, nb::callable law) {
  const Eigen::Index n = plant.model.nv, nz = spec.z0.size();
  std::exception_ptr failure;
  const nnrobust::ExternalLaw external = [&](double t, const nnrobust::Vector &q, const nnrobust::Vector &v,
                                             const nnrobust::Vector &z, nnrobust::Vector &tau,
                                             nnrobust::Vector &z_next) -> bool {
    try {
      nb::object result = law(t, q, v, z);
      if (result.is_none()) return false;  // interrupted (Ctrl-C, SIGTERM inside the law)
      nb::tuple out = nb::cast<nb::tuple>(result);
      if (out.size() != 2) throw std::invalid_argument("the hybrid law must return (tau, z_next)");
      tau = nb::cast<nnrobust::Vector>(out[0]);
      z_next = nb::cast<nnrobust::Vector>(out[1]);
      if (tau.size() != n || z_next.size() != nz)
        throw std::length_error("the hybrid law returned a torque of " + std::to_string(tau.size()) +
                                " entries (needs " + std::to_string(n) + ") or a state of " +
                                std::to_string(z_next.size()) + " (needs " + std::to_string(nz) + ")");
      return true;
    } catch (...) {
      failure = std::current_exception();
      return false;
    }
  };
  LoopTrace trace = nnrobust::run_loop(plant, nullptr, spec, &python_signal_pending, &external);
  if (failure) std::rethrow_exception(failure);
  if (trace.status == "failed") trace.status = "interrupted";
  return trace;
}

// A batch: the models and specs stay owned by Python (kept alive by the call's arguments).
std::vector<LoopTrace> batch(std::vector<LoadedModel *> plants, std::vector<LoadedModel *> nominals,
                             std::vector<const LoopSpec *> specs, int threads) {
  if (plants.size() != specs.size() || nominals.size() != specs.size())
    throw std::invalid_argument("run_batch: plants, nominals and specs must have the same length");
  std::vector<nnrobust::BatchItem> items;
  for (size_t i = 0; i < specs.size(); ++i) {
    if (specs[i]->nominal == "pinocchio" && nominals[i] == nullptr)
      throw std::invalid_argument("run_batch: the nominal model 'pinocchio' needs its model");
    items.push_back({plants[i], nominals[i], specs[i]});
  }
  nb::gil_scoped_release released;
  return nnrobust::run_batch(items, threads, &python_signal_pending);
}

}  // namespace

NB_MODULE(_loop, m) {
  m.doc() = "The compiled closed loop of nnrobust (Pinocchio C++ API).";
  nb::class_<ModelSpec>(m, "ModelSpec", "A Pinocchio model as numbers (nnrobust/compiled.py, model_spec).")
      .def(nb::init<>())
      .def_rw("joint_types", &ModelSpec::joint_types)
      .def_rw("joint_names", &ModelSpec::joint_names)
      .def_rw("parents", &ModelSpec::parents)
      .def_rw("axes", &ModelSpec::axes)
      .def_rw("rotations", &ModelSpec::rotations)
      .def_rw("translations", &ModelSpec::translations)
      .def_rw("inertias", &ModelSpec::inertias)
      .def_rw("armature", &ModelSpec::armature)
      .def_rw("gravity", &ModelSpec::gravity)
      .def_rw("frame_name", &ModelSpec::frame_name)
      .def_rw("frame_joint", &ModelSpec::frame_joint)
      .def_rw("frame_rotation", &ModelSpec::frame_rotation)
      .def_rw("frame_translation", &ModelSpec::frame_translation);
  nb::class_<LoadedModel>(m, "LoadedModel", "A Pinocchio model rebuilt on the C++ side from a ModelSpec.")
      .def(nb::init<const ModelSpec &>(), nb::arg("spec"))
      .def_prop_ro("nq", &LoadedModel::nq)
      .def("mass", &LoadedModel::mass, nb::arg("q"), "M(q) [kg m^2].")
      .def("bias", &LoadedModel::bias, nb::arg("q"), nb::arg("v"), "V_m(q, v) v + G(q) [N m].")
      .def("frame_jacobian", &LoadedModel::frame_jacobian, nb::arg("q"),
           "6 x n Jacobian of the task frame, world-aligned axes.");
  nb::class_<LoopSpec> spec(m, "LoopSpec", "Everything one compiled run needs (nnrobust/compiled.py).");
  spec.def(nb::init<>());
#define FIELD(name) spec.def_rw(#name, &LoopSpec::name)
  FIELD(period); FIELD(substeps); FIELD(max_step_rotation); FIELD(max_period_substeps); FIELD(steps);
  FIELD(max_speed); FIELD(q0); FIELD(v0); FIELD(plant_params); FIELD(plant_parts); FIELD(nominal);
  FIELD(nominal_params); FIELD(m); FIELD(nominal_friction); FIELD(path); FIELD(path_params); FIELD(pose);
  FIELD(pose_params); FIELD(law); FIELD(law_params); FIELD(law_signals); FIELD(robust); FIELD(robust_params);
  FIELD(criteria); FIELD(criterion_params); FIELD(criterion_weights); FIELD(pinv_threshold);
  FIELD(pinv_max_damping); FIELD(z0);
#undef FIELD
  nb::class_<LoopTrace>(m, "LoopTrace", "The arrays of a compiled run (nnrobust.simulation.Trace).")
      .def_ro("q", &LoopTrace::q)
      .def_ro("dq", &LoopTrace::dq)
      .def_ro("tau", &LoopTrace::tau)
      .def_ro("tau_cmd", &LoopTrace::tau_cmd)
      .def_ro("z", &LoopTrace::z)
      .def_ro("signals", &LoopTrace::signals)
      .def_ro("chain", &LoopTrace::chain)
      .def_ro("manipulability", &LoopTrace::manipulability)
      .def_ro("h", &LoopTrace::h)
      .def_ro("done", &LoopTrace::done)
      .def_ro("status", &LoopTrace::status)
      .def_ro("divergence_index", &LoopTrace::divergence_index)
      .def_ro("divergence_joint", &LoopTrace::divergence_joint)
      .def_ro("friction_events", &LoopTrace::friction_events)
      .def_ro("unresolved_events", &LoopTrace::unresolved_events)
      .def_ro("refined_periods", &LoopTrace::refined_periods);
  m.def("run_loop", &run, nb::arg("plant"), nb::arg("spec"), nb::arg("nominal").none() = nb::none(),
        "Run the compiled closed loop (GIL released; Ctrl-C and SIGTERM stop it); `nominal` is the "
        "controller's Pinocchio model when spec.nominal is 'pinocchio'.");
  m.def("run_hybrid", &hybrid, nb::arg("plant"), nb::arg("spec"), nb::arg("law"),
        "Run the compiled plant with a Python control law law(t, q, v, z) -> (tau, z_next), called once "
        "per control period (the GIL held); an exception of the law stops the run and is raised.");
  m.def("run_batch", &batch, nb::arg("plants"), nb::arg("nominals"), nb::arg("specs"), nb::arg("threads"),
        "Run several loops on C++ threads with the GIL released (one model pair per run; None "
        "nominals for the closed form); Ctrl-C and SIGTERM stop them all.");
  // each compiled component alone, for the twin tests (tests/test_twins.py)
  nb::class_<nnrobust::ControlStep>(m, "ControlStep", "One compiled control step's output.")
      .def_ro("tau", &nnrobust::ControlStep::tau)
      .def_ro("z", &nnrobust::ControlStep::z)
      .def_ro("signals", &nnrobust::ControlStep::signals);
  m.def("twin_control", &nnrobust::twin_control, nb::arg("nominal").none(), nb::arg("spec"), nb::arg("t"),
        nb::arg("q"), nb::arg("v"), nb::arg("z"), "The compiled law's output and next state at one state.");
  m.def("twin_criterion_gradient", &nnrobust::twin_criterion_gradient, nb::arg("nominal").none(), nb::arg("spec"),
        nb::arg("q"), "The compiled weighted criterion's gradient on the nominal model at q.");
  m.def("twin_criterion_value", &nnrobust::twin_criterion_value, nb::arg("robot"), nb::arg("spec"), nb::arg("q"),
        "The compiled weighted criterion's value on the true robot at q (as recorded).");
  m.def("twin_plant_acceleration", &nnrobust::twin_plant_acceleration, nb::arg("plant"), nb::arg("spec"),
        nb::arg("t"), nb::arg("q"), nb::arg("v"), nb::arg("tau"),
        "The compiled plant's q'' at (t, q, v) under the applied torque tau, the loads held from t.");
}
