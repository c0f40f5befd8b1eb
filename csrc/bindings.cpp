// nnrobust._loop: the one binding module of the compiled backend (docs/compiled.md).
#include <nanobind/eigen/dense.h>
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/map.h>
#include <nanobind/stl/pair.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

#include <Python.h>
#include <cxxabi.h>
#include <dlfcn.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <functional>
#include <mutex>
#include <optional>
#include <set>
#include <sstream>
#include <thread>
#include <stdexcept>
#include <string>

#include "closed_loop.hpp"
#include "controllers.hpp"
#include "controllers/laws/law.hpp"
#include "controllers/robust_term.hpp"
#include "plant/disturbance.hpp"
#include "learning.hpp"
#include "model/model.hpp"
#include "model/regressor.hpp"
#include "serve/virtual_robot.hpp"
#include "user_code.hpp"

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

// The laws compiled apart (a user's, a twin's), by the name they are registered under, each with
// the label its errors name it by (the file it was last loaded from: two files of the same
// content share one library): their runs take the stop signals' watchdog (user_code.hpp); a
// shipped law's run takes nothing.
std::mutex user_laws_lock;
std::map<std::string, const char *> &user_laws() {
  static std::map<std::string, const char *> laws;
  return laws;
}

bool is_user_law(const std::string &name) {
  const std::lock_guard<std::mutex> hold(user_laws_lock);
  return user_laws().count(name) != 0;
}

const char *user_law_label(const std::string &name) {
  const std::lock_guard<std::mutex> hold(user_laws_lock);
  const auto it = user_laws().find(name);
  return it == user_laws().end() ? nnrobust::user_label("the law " + name) : it->second;
}

void set_user_law(const std::string &name, const char *label) {
  const std::lock_guard<std::mutex> hold(user_laws_lock);
  user_laws()[name] = label;
}

LoopTrace run(LoadedModel &plant, const LoopSpec &spec, LoadedModel *nominal) {
  if (spec.nominal == "pinocchio" && nominal == nullptr)
    throw std::invalid_argument("the nominal model 'pinocchio' needs its model");
  std::optional<nnrobust::StopWatchdog> watchdog;
  if (is_user_law(spec.law)) watchdog.emplace();
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

// A user's law compiled apart (nnrobust/native_law.py): its library loaded, its factory registered
// as the law `name`. The library's calls into the extension (Controller's, Fields') resolve
// against this module, made global once; its three NNROBUST_USER_LAW functions are looked up.
std::map<std::string, int (*)(int)> &native_states() {
  static std::map<std::string, int (*)(int)> states;
  return states;
}

// A library compiled apart calls into the extension (Controller's, Fields'): this module's
// exported symbols are made global once, before the first such library is loaded.
void offer_symbols() {
  static bool global = false;
  if (global) return;
  Dl_info self;
  if (dladdr(reinterpret_cast<void *>(&python_signal_pending), &self) == 0 || self.dli_fname == nullptr ||
      dlopen(self.dli_fname, RTLD_NOW | RTLD_NOLOAD | RTLD_GLOBAL) == nullptr)
    throw std::runtime_error("the compiled loop could not offer its symbols to a library compiled apart");
  global = true;
}

// The library at `path`, known as `label` (user_code.hpp: its exits and crashes are said so).
void *open_library(const std::string &path, const char *label) {
  offer_symbols();
  nnrobust::name_library(path, label);
  void *library = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (library == nullptr) throw std::runtime_error(std::string("loading ") + path + ": " + dlerror());
  return library;
}

// The exception being handled, as "std::out_of_range: what it said".
std::string current_exception_text() {
  std::string type = "an exception";
  if (const std::type_info *info = abi::__cxa_current_exception_type()) {
    int status = 0;
    char *name = abi::__cxa_demangle(info->name(), nullptr, nullptr, &status);
    type = status == 0 && name ? name : info->name();
    std::free(name);
  }
  try {
    throw;
  } catch (const std::exception &err) {
    return type + ": " + err.what();
  } catch (...) {
    return type + " (not a std::exception)";
  }
}

std::string seconds_text(double t) {
  std::ostringstream out;
  out << t;
  return out.str();
}

// A law compiled apart, run inside a UserCodeScope (user_code.hpp) with its output checked: an
// exception it throws, a torque, state or signals of another size are one UserLawError naming
// it and its file. The shipped laws are called directly.
struct GuardedLaw final : nnrobust::Law {
  std::unique_ptr<nnrobust::Law> inner;
  const char *label;
  Eigen::Index state_size, signals;

  GuardedLaw(std::unique_ptr<nnrobust::Law> law, const char *who, const LoopSpec &spec)
      : inner(std::move(law)), label(who), state_size(spec.z0.size()), signals(spec.law_signals) {}
  ~GuardedLaw() override {
    nnrobust::UserCodeScope scope(label, "its destructor");
    inner.reset();
  }

  nnrobust::Output compute(double t, const nnrobust::Vector &q, const nnrobust::Vector &v,
                           const nnrobust::Vector &z) override {
    nnrobust::Output out;
    {
      nnrobust::UserCodeScope scope(label, "its compute");
      try {
        out = inner->compute(t, q, v, z);
      } catch (...) {
        throw nnrobust::UserLawError(std::string(label) + " threw in its compute at t = " + seconds_text(t) +
                                     " s: " + current_exception_text());
      }
    }
    const auto wrong = [&](Eigen::Index size, const std::string &what, const std::string &why) {
      return nnrobust::UserLawError(std::string(label) + " returned " + what + " of " + std::to_string(size) +
                                    " entries at t = " + seconds_text(t) + " s; " + why);
    };
    if (out.tau.size() != q.size())
      throw wrong(out.tau.size(), "a torque", "the arm has " + std::to_string(q.size()) + " joints");
    if (out.z.size() != state_size)
      throw wrong(out.z.size(), "a state",
                  "its state size is " + std::to_string(state_size) + " (NNROBUST_USER_LAW's third argument)");
    if (out.signals.size() != signals)
      throw wrong(out.signals.size(), "signals",
                  "it declares " + std::to_string(signals) + " (NNROBUST_USER_LAW's second argument)");
    return out;
  }

  bool scale_gains(double position, double velocity) override {
    nnrobust::UserCodeScope scope(label, "its scale_gains");
    return inner->scale_gains(position, velocity);
  }
};

// The factory of the law compiled apart registered as `name`, guarded, each law it builds named by
// the label `name` has then (user_laws).
template <class Make>
nnrobust::LawRegistry::Factory guarded(Make make, const std::string &name) {
  return [make, name](const nnrobust::LawParams &p, nnrobust::LawContext &c) -> std::unique_ptr<nnrobust::Law> {
    const char *label = user_law_label(name);
    const std::string owner = "controller.params";
    const nnrobust::LawParams params{owner, p.values};  // a missing field is said as the user's parameter
    std::unique_ptr<nnrobust::Law> law;
    {
      nnrobust::UserCodeScope scope(label, "its constructor");
      try {
        law = make(params, c);
      } catch (...) {
        throw nnrobust::UserLawError(std::string(label) + " could not be built: " + current_exception_text());
      }
    }
    if (!law) throw nnrobust::UserLawError(std::string(label) + " could not be built: its factory gave no law");
    return std::make_unique<GuardedLaw>(std::move(law), label, c.spec);
  };
}

std::pair<std::string, std::string> load_law_library(const std::string &path, const std::string &cls,
                                                     const std::string &name, const std::string &label) {
  const char *who = nnrobust::user_label(label.empty() ? "the law " + cls + " (" + path + ")" : label);
  void *library = open_library(path, who);
  using Make = nnrobust::Law *(*)(const nnrobust::LawParams &, nnrobust::LawContext &);
  const auto make = reinterpret_cast<Make>(dlsym(library, ("nnrobust_law_factory_" + cls).c_str()));
  const auto signals = reinterpret_cast<const char *(*)()>(dlsym(library, ("nnrobust_law_signals_" + cls).c_str()));
  const auto state = reinterpret_cast<int (*)(int)>(dlsym(library, ("nnrobust_law_state_" + cls).c_str()));
  if (make == nullptr || signals == nullptr || state == nullptr)
    throw std::invalid_argument("it has no NNROBUST_USER_LAW(" + cls + ", signals, state size) at global scope");
  set_user_law(name, who);
  nnrobust::LawRegistry::add(
      name, guarded([make](const nnrobust::LawParams &p, nnrobust::LawContext &c) { return std::unique_ptr<nnrobust::Law>(make(p, c)); },
                    name));
  native_states()[name] = state;
  const auto space = reinterpret_cast<const char *(*)()>(dlsym(library, ("nnrobust_law_space_" + cls).c_str()));
  nnrobust::UserCodeScope scope(who, "its NNROBUST_USER_LAW declarations");
  return {signals(), space ? space() : ""};
}

// A twin compiled apart (nnrobust/native_law.py, nnrobust/twin.hpp): a library whose file registers
// components with the shipped macros (NNROBUST_PATH, NNROBUST_CRITERION, NNROBUST_DISTURBANCE,
// NNROBUST_ROBUST_TERM, NNROBUST_LAW) into its own tables; each table it has is copied into this
// module's. A name a shipped twin holds is refused; a name an earlier library registered is taken
// over (the newer file). Returns {concept: comma-separated names}.
std::set<std::string> split_names(const std::string &names) {
  std::set<std::string> out;
  std::stringstream stream(names);
  for (std::string name; std::getline(stream, name, ',');)
    if (!name.empty()) out.insert(name);
  return out;
}

// The names the twin libraries loaded so far registered, of every concept (load_twin_library)
std::set<std::string> &twin_names() {
  static std::set<std::string> names;
  return names;
}

// nnrobust::law_in_arena: the law and the parts it names are all this module's, none compiled
// apart (a user's law, a twin library's component), whose code allocates outside the arena
bool all_shipped(const nnrobust::LoopSpec &s) {
  if (is_user_law(s.law)) return false;
  const std::lock_guard<std::mutex> hold(user_laws_lock);
  const std::set<std::string> &apart = twin_names();
  if (apart.count(s.law) || apart.count(s.robust) || apart.count(s.path)) return false;
  for (const std::string &c : s.criteria)
    if (apart.count(c)) return false;
  return true;
}

std::map<std::string, std::string> load_twin_library(const std::string &path, const std::string &label) {
  using HandOver = const char *(*)(void *);
  struct Shared {
    std::string concept;
    const char *symbol;
    HandOver own;  // this module's table of the registry, listed
    void *table;
  };
  const Shared shares[] = {
      {"law", "nnrobust_twin_laws", &nnrobust::share_registry<nnrobust::LawRegistry>,
       &nnrobust::LawRegistry::table()},
      {"robust term", "nnrobust_twin_robust_terms", &nnrobust::share_registry<nnrobust::RobustTermRegistry>,
       &nnrobust::RobustTermRegistry::table()},
      {"criterion", "nnrobust_twin_criteria", &nnrobust::share_registry<nnrobust::CriterionRegistry>,
       &nnrobust::CriterionRegistry::table()},
      {"path", "nnrobust_twin_paths", &nnrobust::share_registry<nnrobust::PathRegistry>,
       &nnrobust::PathRegistry::table()},
      {"disturbance", "nnrobust_twin_disturbances", &nnrobust::share_registry<nnrobust::DisturbanceRegistry>,
       &nnrobust::DisturbanceRegistry::table()},
  };
  static std::map<std::string, std::set<std::string>> shipped;  // each concept's names before any library
  if (shipped.empty())
    for (const Shared &share : shares) shipped[share.concept] = split_names(share.own(nullptr));
  const char *who = nnrobust::user_label(label.empty() ? "the twin library " + path : label);
  void *library = open_library(path, who);
  std::map<std::string, std::string> registered;
  for (const Shared &share : shares) {
    const auto hand_over = reinterpret_cast<HandOver>(dlsym(library, share.symbol));
    if (hand_over == nullptr) continue;
    const std::string names = hand_over(nullptr);
    for (const auto &name : split_names(names))
      if (shipped[share.concept].count(name))
        throw std::invalid_argument("it registers the " + share.concept + " '" + name +
                                    "', the name of a shipped twin: choose another name");
    if (!names.empty()) registered[share.concept] = names;
  }
  if (registered.empty())
    throw std::invalid_argument("it registers nothing: a twin's file includes nnrobust/twin.hpp and names its class "
                                "with NNROBUST_PATH, NNROBUST_CRITERION, NNROBUST_DISTURBANCE, "
                                "NNROBUST_ROBUST_TERM or NNROBUST_LAW at namespace scope");
  {
    const std::lock_guard<std::mutex> hold(user_laws_lock);
    for (const auto &[concept, names] : registered)
      for (const auto &name : split_names(names)) twin_names().insert(name);
  }
  for (const Shared &share : shares)
    if (registered.count(share.concept)) reinterpret_cast<HandOver>(dlsym(library, share.symbol))(share.table);
  if (registered.count("law"))  // its laws are guarded as a user's law is
    for (const auto &name : split_names(registered["law"])) {
      const std::string law_label = "the law " + name + " of " + who;
      set_user_law(name, nnrobust::user_label(law_label));
      auto &table = nnrobust::LawRegistry::table();
      table[name] = guarded(table[name], name);
    }
  return registered;
}

int native_law_state(const std::string &name, int n) {
  const auto it = native_states().find(name);
  if (it == native_states().end()) throw std::invalid_argument("no law library registered " + name);
  return it->second(n);
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
  std::optional<nnrobust::StopWatchdog> watchdog;
  for (const auto *spec : specs)
    if (!watchdog && is_user_law(spec->law)) watchdog.emplace();
  nb::gil_scoped_release released;
  return nnrobust::run_batch(items, threads, &python_signal_pending);
}


// The learning environment (nnrobust/learning/, csrc/learning.hpp): the vector environment's
// step on the pool, GIL released. Arrays are C-contiguous with one row per loop.
using nnrobust::SteppedLoop;
template <typename T>
using RowsOf = nb::ndarray<T, nb::ndim<2>, nb::c_contig, nb::device::cpu>;
template <typename T>
using ColumnOf = nb::ndarray<T, nb::ndim<1>, nb::c_contig, nb::device::cpu>;

void step_loops(nnrobust::StepPool &pool, std::vector<SteppedLoop *> loops, const nnrobust::RewardSpec &spec,
                RowsOf<const double> actions, ColumnOf<const double> sizes, RowsOf<double> observations,
                RowsOf<double> applied, ColumnOf<double> rewards, ColumnOf<bool> running) {
  const size_t count = loops.size();
  if (actions.shape(0) != count || observations.shape(0) != count || applied.shape(0) != count ||
      rewards.shape(0) != count || running.shape(0) != count || sizes.shape(0) != count)
    throw std::invalid_argument("step_loops: every array needs one row per loop");
  const size_t na = static_cast<size_t>(spec.action_scale.size());
  const size_t n = static_cast<size_t>(spec.torque_limit.size());
  if (spec.mode == nnrobust::ACTION_GAINS ? na != 2 : na != n)
    throw std::invalid_argument("step_loops: spec.action_scale needs " + std::string(spec.mode == nnrobust::ACTION_GAINS ? "2" : "one per joint") + " entries");
  for (size_t i = 0; i < count; ++i) {
    if (loops[i] == nullptr) throw std::invalid_argument("step_loops: loop " + std::to_string(i) + " is None");
    const SteppedLoop &loop = *loops[i];
    if (static_cast<size_t>(loop.measured_q().size()) != n || actions.shape(1) != na || applied.shape(1) != n ||
        static_cast<int>(observations.shape(1)) != loop.observation_size() || spec.torque_limit.size() != n ||
        spec.lower.size() != n || spec.upper.size() != n || spec.speed_limit.size() != n)
      throw std::invalid_argument("step_loops: loop " + std::to_string(i) + " needs actions of " +
                                  std::to_string(na) + ", torques of " + std::to_string(loop.measured_q().size()) + " and observations of " +
                                  std::to_string(loop.observation_size()) + " entries, and limits of its joints");
    if (!loop.running()) throw std::invalid_argument("step_loops: loop " + std::to_string(i) + " has ended");
  }
  const nnrobust::StepRows rows{actions.data(), observations.data(), applied.data(), rewards.data(),
                                running.data(), sizes.data(),        na,             observations.shape(1),
                                n};
  nb::gil_scoped_release released;
  nnrobust::step_loops(pool, loops, spec, rows);
}
}  // namespace

NB_MODULE(_loop, m) {
  m.doc() = "The compiled closed loop of nnrobust (Pinocchio C++ API).";
  nnrobust::law_in_arena = &all_shipped;
  m.def("law_in_arena", &nnrobust::law_runs_in_arena,
        "Whether a run of this spec takes its compiled law's temporaries from the loop's arena (its step "
        "then calls no system allocator): the allocator is wrapped and the law and its parts are all the "
        "module's own.");
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
  m.def(
      "torque_regressor",
      [](LoadedModel &model, const nnrobust::Rows &q, const nnrobust::Rows &v, const nnrobust::Rows &a) {
        const Eigen::Index N = q.rows(), n = model.model.nv, p = 10 * (model.model.njoints - 1);
        if (q.cols() != model.model.nq || v.rows() != N || a.rows() != N || v.cols() != n || a.cols() != n)
          throw std::invalid_argument("torque_regressor: q, v and a must be N x " + std::to_string(n) +
                                      " rows of the same N");
        nnrobust::Rows out(N * n, p);
        {
          nb::gil_scoped_release released;
          nnrobust::Matrix Y = nnrobust::Matrix::Zero(n, p);
          nnrobust::Vector qk(q.cols()), vk(n), ak(n);
          for (Eigen::Index k = 0; k < N; ++k) {
            qk = q.row(k).transpose();
            vk = v.row(k).transpose();
            ak = a.row(k).transpose();
            nnrobust::joint_torque_regressor(model.model, model.data, qk, vk, ak, Y);
            out.middleRows(k * n, n) = Y;
          }
        }
        return out;
      },
      "The joint torque regressor Y(q, q', q'') of N states (rows of q, v, a), stacked: (N n) x 10 n, "
      "Y phi = M(q) q'' + N(q, q') (nnrobust.model.regressor.torque_regressor's twin, one C++ call).");
  nb::class_<LoopSpec> spec(m, "LoopSpec", "Everything one compiled run needs (nnrobust/compiled.py).");
  spec.def(nb::init<>());
#define FIELD(name) spec.def_rw(#name, &LoopSpec::name)
  FIELD(period); FIELD(substeps); FIELD(max_step_rotation); FIELD(max_period_substeps); FIELD(steps);
  FIELD(max_speed); FIELD(q0); FIELD(v0); FIELD(plant_params); FIELD(plant_parts); FIELD(disturbance); FIELD(nominal);
  FIELD(nominal_params); FIELD(m); FIELD(nominal_friction); FIELD(path); FIELD(path_params); FIELD(pose);
  FIELD(pose_params); FIELD(law); FIELD(law_params); FIELD(law_signals); FIELD(robust); FIELD(robust_params);
  FIELD(criteria); FIELD(criterion_params); FIELD(criterion_weights); FIELD(pinv_threshold);
  FIELD(pinv_max_damping); FIELD(z0); FIELD(profile);
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
      .def_ro("refined_periods", &LoopTrace::refined_periods)
      .def_ro("part_seconds", &LoopTrace::part_seconds)
      .def_ro("part_allocations", &LoopTrace::part_allocations);
  m.attr("LOOP_PARTS") = nb::make_tuple(nnrobust::kLoopPartNames[0], nnrobust::kLoopPartNames[1],
                                        nnrobust::kLoopPartNames[2], nnrobust::kLoopPartNames[3],
                                        nnrobust::kLoopPartNames[4]);
  m.def("run_loop", &run, nb::arg("plant"), nb::arg("spec"), nb::arg("nominal").none() = nb::none(),
        "Run the compiled closed loop (GIL released; Ctrl-C and SIGTERM stop it); `nominal` is the "
        "controller's Pinocchio model when spec.nominal is 'pinocchio'.");
  m.def("run_hybrid", &hybrid, nb::arg("plant"), nb::arg("spec"), nb::arg("law"),
        "Run the compiled plant with a Python control law law(t, q, v, z) -> (tau, z_next), called once "
        "per control period (the GIL held); an exception of the law stops the run and is raised.");
  m.def("run_batch", &batch, nb::arg("plants"), nb::arg("nominals"), nb::arg("specs"), nb::arg("threads"),
        "Run several loops on C++ threads with the GIL released (one model pair per run; None "
        "nominals for the closed form); Ctrl-C and SIGTERM stop them all.");
  // the learning environment's loop (nnrobust/learning/)
  nb::class_<SteppedLoop>(m, "SteppedLoop",
                          "The closed loop one control period at a time (the learning environment).")
      .def(nb::init<LoadedModel &, LoadedModel *, const LoopSpec &, bool>(), nb::arg("plant"),
           nb::arg("nominal").none(), nb::arg("spec"), nb::arg("with_law"), nb::keep_alive<1, 2>(),
           nb::keep_alive<1, 3>(), nb::keep_alive<1, 4>())
      .def_prop_ro("running", &SteppedLoop::running)
      .def_prop_ro("step", &SteppedLoop::step)
      .def_prop_ro("time", &SteppedLoop::time)
      .def_prop_ro("observation_size", &SteppedLoop::observation_size)
      .def_prop_ro("measured_q", &SteppedLoop::measured_q)
      .def_prop_ro("measured_v", &SteppedLoop::measured_v)
      .def_prop_ro("applied_torque", &SteppedLoop::applied_torque)
      .def_prop_ro("status", [](const SteppedLoop &l) { return l.trace().status; })
      .def(
          "observe",
          [](const SteppedLoop &l) {
            nnrobust::Vector obs(l.observation_size());
            l.observe(obs.data());
            return obs;
          },
          "The observation at the current control instant (docs/learning.md).")
      .def(
          "observe_into",
          [](const SteppedLoop &l, ColumnOf<double> out) {
            if (static_cast<int>(out.shape(0)) != l.observation_size())
              throw std::invalid_argument("SteppedLoop.observe_into: needs an array of " +
                                          std::to_string(l.observation_size()) + " entries");
            l.observe(out.data());
          },
          nb::arg("out"), "Write the observation at the current control instant into `out` (float64, in place).")
      .def(
          "act_action",
          [](SteppedLoop &l, const nnrobust::Vector &action, const nnrobust::Vector &scale, int mode) {
            if (action.size() != scale.size())
              throw std::invalid_argument("SteppedLoop.act_action: the action needs " + std::to_string(scale.size()) +
                                          " entries, got " + std::to_string(action.size()));
            if (!l.running()) throw std::invalid_argument("SteppedLoop.act_action: the run has ended (" + l.trace().status + ")");
            if (!action.allFinite()) return -1;
            return nnrobust::step_action(l, action.data(), scale, mode) ? 1 : 0;
          },
          nb::arg("action"), nb::arg("scale"), nb::arg("mode"),
          "One control period under a policy's raw action: clipped to [-1, 1], times `scale`, applied as "
          "`mode` says (act's modes). 1: the run goes on, 0: it has ended, -1: the action is not finite "
          "(nothing applied).")
      .def(
          "act",
          [](SteppedLoop &l, const nnrobust::Vector &command, int mode) {
            const Eigen::Index size = mode == nnrobust::ACTION_GAINS ? 2 : l.measured_q().size();
            if (command.size() != size)
              throw std::invalid_argument("SteppedLoop.act: the command needs " + std::to_string(size) +
                                          " entries, got " + std::to_string(command.size()));
            if (!l.running()) throw std::invalid_argument("SteppedLoop.act: the run has ended (" + l.trace().status + ")");
            return nnrobust::apply_command(l, command, mode);
          },
          nb::arg("command"), nb::arg("mode"),
          "One control period: mode 0 applies `command` [N m], mode 1 adds it to the compiled law's, mode 2 "
          "multiplies the law's position and velocity gains by exp(command) (2 entries); False when the run "
          "has ended.")
      .def(
          "control",
          [](SteppedLoop &l) {
            if (!l.running()) throw std::invalid_argument("SteppedLoop.control: the run has ended (" + l.trace().status + ")");
            const nnrobust::Output out = l.control();
            return nnrobust::ControlStep{out.tau, out.z, out.signals};
          },
          "The compiled law's output at the current instant from the measurement and the state (nothing "
          "applied): what an exported law returns there (docs/export.md).")
      .def("end", &SteppedLoop::end, nb::arg("status"), "Stop the run here, marked `status`.")
      .def("finish", &SteppedLoop::finish, "The run's trace (call once, at the end).");
  nb::class_<nnrobust::StepPool>(m, "StepPool", "A persistent pool of C++ threads stepping loops.")
      .def(nb::init<int>(), nb::arg("threads"))
      .def_prop_ro("threads", &nnrobust::StepPool::threads);
  nb::class_<nnrobust::RewardSpec> reward(m, "RewardSpec", "The reward's weights and the arm's limits.");
  reward.def(nb::init<>());
#define FIELD(name) reward.def_rw(#name, &nnrobust::RewardSpec::name)
  FIELD(error); FIELD(effort); FIELD(limits); FIELD(torque_limit); FIELD(lower); FIELD(upper);
  FIELD(speed_limit); FIELD(action_scale); FIELD(mode);
#undef FIELD
  m.def("step_loops", &step_loops, nb::arg("pool"), nb::arg("loops"), nb::arg("spec"), nb::arg("actions"),
        nb::arg("sizes"), nb::arg("observations"), nb::arg("applied"), nb::arg("rewards"), nb::arg("running"),
        "One control period of every loop on the pool's threads (GIL released): loop i takes the raw "
        "action actions[i] (clipped to [-1, 1], scaled by spec.action_scale, as spec.mode says) and "
        "writes its next observation, applied torque, reward and whether it runs on.");
  nb::exception<nnrobust::UserLawError>(m, "UserLawError", PyExc_RuntimeError);
  m.def("load_law_library", &load_law_library, nb::arg("path"), nb::arg("cls"), nb::arg("name"),
        nb::arg("label") = "",
        "Load a user's law compiled apart and register it as the law `name`, said as `label` in its "
        "errors; returns its signal names and its search space as declared (comma-separated; \"\" "
        "when it declares none).");
  m.def("load_twin_library", &load_twin_library, nb::arg("path"), nb::arg("label") = "",
        "Load a twin compiled apart (nnrobust/twin.hpp) and register its components; returns the names "
        "it registered by concept (law, robust term, criterion, path, disturbance), comma-separated.");
  m.def(
      "name_law", [](const std::string &name, const std::string &label) { set_user_law(name, nnrobust::user_label(label)); },
      nb::arg("name"), nb::arg("label"),
      "Name the law library registered as `name` by `label` in its errors from now on (the file it "
      "is loaded from again: the same content in another file shares its library).");
  m.def("native_law_state", &native_law_state, nb::arg("name"), nb::arg("n"),
        "The state size of the law library registered as `name`, for n joints.");
  // the virtual robot (nnrobust/serve/, csrc/serve/)
  nb::class_<nnrobust::ServeReport>(m, "ServeReport", "What a served run's timing and protocol did.")
      .def_ro("periods", &nnrobust::ServeReport::periods)
      .def_ro("accepted", &nnrobust::ServeReport::accepted)
      .def_ro("misses", &nnrobust::ServeReport::misses)
      .def_ro("rejected", &nnrobust::ServeReport::rejected)
      .def_ro("events", &nnrobust::ServeReport::events)
      .def_ro("latency", &nnrobust::ServeReport::latency)
      .def_ro("lateness", &nnrobust::ServeReport::lateness)
      .def_ro("stopped", &nnrobust::ServeReport::stopped)
      .def_ro("connected", &nnrobust::ServeReport::connected)
      .def_ro("scheduling", &nnrobust::ServeReport::scheduling);
  nb::class_<nnrobust::VirtualRobot>(m, "VirtualRobot",
                                     "The compiled plant paced by the wall clock, served over UDP (docs/serve.md).")
      .def(
          "__init__",
          [](nnrobust::VirtualRobot *self, LoadedModel &plant, const LoopSpec &spec, const std::string &host, int port,
             double wait_seconds, int watchdog, bool realtime, bool lockstep) {
            nnrobust::ServeOptions options;
            options.realtime = realtime;
            options.lockstep = lockstep;
            options.host = host;
            options.port = port;
            options.wait_seconds = wait_seconds;
            options.watchdog = watchdog;
            new (self) nnrobust::VirtualRobot(plant, spec, options);
          },
          nb::arg("plant"), nb::arg("spec"), nb::arg("host"), nb::arg("port"), nb::arg("wait_seconds"),
          nb::arg("watchdog"), nb::arg("realtime"), nb::arg("lockstep"), nb::keep_alive<1, 2>(),
          nb::keep_alive<1, 3>())
      .def_prop_ro("port", &nnrobust::VirtualRobot::port)
      .def(
          "run",
          [](nnrobust::VirtualRobot &robot) {
            nb::gil_scoped_release released;
            return robot.run(&python_signal_pending);
          },
          "Wait for a controller's HELLO, then run the experiment in real time (GIL released).")
      .def("finish", &nnrobust::VirtualRobot::finish, "The run's trace (call once, after run).");
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
