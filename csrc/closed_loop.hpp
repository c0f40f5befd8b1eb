// The compiled closed loop: the C++ twin of nnrobust.simulation.simulate for the components that
// have a compiled twin (docs/compiled.md). Every formula mirrors its Python reference, named in
// the comments; tests/test_compiled.py holds the two equal.
#pragma once

#include <functional>
#include <memory>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "fields.hpp"
#include "model/model.hpp"

namespace nnrobust {

// Row-major: a step reads or writes one contiguous row of each per-step array (a column-major
// steps x n array would make every recorded value a cache miss, which dominated the step for
// long chains).
using Rows = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// Everything one run needs, filled in by nnrobust/compiled.py from a built experiment. There are
// no defaults here (Python's are the only ones): the laws, robust terms, paths and criteria read
// their fields by name from the maps below (a missing one is an error naming it), and the numbers
// listed here start as NaN, so one the Python side did not fill poisons the run (status
// "diverged") instead of running silently with a value that disagrees with Python's.
constexpr double unset = std::numeric_limits<double>::quiet_NaN();

struct LoopSpec {
  // simulation
  double period = 1e-3;
  int substeps = 1;
  // simulation.period_substeps: a period whose fastest joint would turn more than this in one plant
  // step is cut into ceil(period * |v|max / max_step_rotation) steps (at most max_period_substeps)
  double max_step_rotation = std::numeric_limits<double>::infinity();
  int max_period_substeps = 10000;
  long steps = 0;
  double max_speed = 1e3;
  Vector q0, v0;
  // the true robot (nnrobust/plant/, csrc/plant/): Plant.twin_fields, and each of its parts'
  // (Plant.twin_parts: friction, disturbance, loads, sensor; stops and engine where there are some);
  // the disturbance is the one registered under `disturbance` (csrc/plant/disturbance.hpp)
  Params plant_params;
  std::map<std::string, Params> plant_parts;
  std::string disturbance = "sinusoid";
  // the controller's nominal model, by its Python class's twin: "closed-form" (ThreeLinkSpec from
  // nominal_params) or "pinocchio" (a second LoadedModel, no fields)
  std::string nominal;
  Params nominal_params;
  int m = 2;  // task rows: 2 (planar: x, y), 3 (position) or 6 (pose: position, then rotation)
  Params nominal_friction;  // the controller's F-hat (Friction.twin_fields)
  // the desired motion (nnrobust/trajectories/): the position path registered under `path`
  // (csrc/trajectories/) with its fields by name (its Python class's twin_fields), and for a pose
  // task (m = 6) PoseTrajectory's orientation fields
  std::string path;
  Params path_params;
  bool pose = false;
  Params pose_params;
  // the law registered under `law` (csrc/controllers/, csrc/controllers/laws/; "external": the hybrid loop's
  // Python law) with its fields by name (Law.twin_values) and its number of signals; the eq. (9)
  // law's robust term registered under `robust` ("" for u_0 = 0) with its fields
  std::string law;
  Params law_params;
  int law_signals = 0;
  std::string robust;
  Params robust_params;
  // WeightedCriteria: each criterion's registered name (csrc/subtasks/), its fields by name (its
  // Python declaration's twin_fields) and its weight (already scaled to sum to C)
  std::vector<std::string> criteria;
  std::vector<Params> criterion_params;
  Vector criterion_weights;
  double pinv_threshold = unset, pinv_max_damping = unset;
  Vector z0;
  // time the step's parts (LoopTrace::part_seconds; benchmarks/loop_profile.py); off in every run
  // the library makes, where it costs one untaken branch per part
  bool profile = false;
};

// The parts of a step LoopSpec::profile times, in LoopTrace::part_seconds' order: the law's
// compute (the compiled law, or the hybrid loop's Python law with its calls), the loop's own
// bookkeeping (the command's delay and the applied torque, the per-step rows, the divergence
// checks), the recorded kinematics of the true robot (chain points, manipulability, criterion),
// the plant's integration over the period (RK4 or the stick-slip integrator), and the sensor's
// next measurement.
enum LoopPart { kPartLaw, kPartBookkeeping, kPartRecord, kPartPlant, kPartMeasure, kLoopParts };
inline const char *const kLoopPartNames[kLoopParts] = {"law", "bookkeeping", "record", "plant", "measure"};

// What simulate() returns (nnrobust.simulation.Trace).
struct LoopTrace {
  Rows q, dq, tau, tau_cmd, z;
  Rows signals;  // the law's signals: steps x LoopSpec.law_signals
  // what Result.from_trace records, from the true robot's kinematics (nnrobust/results.py)
  Rows chain;            // steps x 3(n + 1): joint origins, then the task frame, in world axes
  Vector manipulability; // sqrt(det(J J^T)) of the task Jacobian
  Vector h;              // the weighted criterion (NaN without one)
  long done = 0;
  std::string status = "completed";
  long divergence_index = -1;  // step at which it diverged
  int divergence_joint = -1;   // joint that ran away (-1: non-finite state or torque)
  long friction_events = 0, unresolved_events = 0;  // StickSlipIntegrator's counts
  long refined_periods = 0;                           // periods whose plant step was cut for speed
  // with LoopSpec::profile, per part (LoopPart): seconds, and calls to the system allocator made
  // on the loop's thread (counted only where benchmarks/allocation_counter.cpp is preloaded: NaN
  // otherwise), summed over the run
  Vector part_seconds, part_allocations;
};

// Times the parts of a step (LoopSpec::profile): lap(part) charges the time and allocations since
// the previous lap to `part`.
class PartClock {
 public:
  explicit PartClock(LoopTrace &trace);
  void lap(LoopPart part);

 private:
  LoopTrace &tr_;
  double last_;
  long allocations_;
};

// A control law without a compiled twin (the hybrid loop: a Python controller's compute), called
// once per control period with the measured (q, q') and the state z; it fills tau (n entries)
// and z_next (z's size) and returns false to stop the run (the caller keeps the error).
using ExternalLaw = std::function<bool(double t, const Vector &q, const Vector &v, const Vector &z, Vector &tau,
                                       Vector &z_next)>;

// The buffers of a step's recorded kinematics (closed_loop.cpp's record_kinematics), kept by the
// loop between steps: the frame's 6 x n Jacobian, its task rows J, J J^T, the chain's points.
struct KinematicsWork {
  Eigen::Matrix<double, 6, Eigen::Dynamic> J6;
  Matrix J, JJt, points;
};

// The stages of the plant's RK4 step with the torque held (simulation._rk4_step), kept by the loop.
struct Rk4Work {
  Vector k1v, k2q, k2v, k3q, k3v, k4q, k4v, q_stage;
};

struct Output;
class Arena;
struct Controller;
struct Nominal;
struct Plant;
class StickSlipIntegrator;
struct Criteria;

// The closed loop one control period at a time: what run_loop steps through, and what the
// learning environment (nnrobust/learning/) drives from outside. At each control instant t_k the
// loop holds the sensor's measurement; advance() takes the command computed from it (by the
// compiled law, control(), or by anything else), applies it after the plant's delay, records
// step k and integrates the plant over the period. With `with_law` the compiled controller (its
// nominal model, path and law) is built: control() and observe() need it.
class SteppedLoop {
 public:
  SteppedLoop(LoadedModel &plant, LoadedModel *nominal, const LoopSpec &spec, bool with_law);
  ~SteppedLoop();
  SteppedLoop(const SteppedLoop &) = delete;
  SteppedLoop &operator=(const SteppedLoop &) = delete;

  bool running() const { return k_ < s_.steps && tr_.status == "completed"; }
  long step() const { return k_; }
  double time() const { return static_cast<double>(k_) * s_.period; }
  const Vector &measured_q() const { return qm_; }
  const Vector &measured_v() const { return vm_; }
  const Vector &state() const { return z_; }
  const Vector &applied_torque() const { return tau_; }  // the torque applied over the last period
  const LoopTrace &trace() const { return tr_; }
  int signal_count() const { return s_.law_signals; }
  int task_rows() const { return s_.m; }
  // the compiled law's output at the current instant from the measurement and the state: the
  // loop's own buffer, good until the next call. A law whose code and parts are all this
  // module's (law_in_arena) takes its step's temporaries from the loop's arena, as an exported
  // law does (csrc/export/arena.hpp): its step calls no system allocator
  const Output &control();
  // Law::scale_gains of the compiled law (false: it has no position and velocity gains)
  bool scale_gains(double position, double velocity);
  // the learning environment's observation (docs/learning.md): the measured q, q', the desired
  // position p_d, the task error e and e' (from the nominal model at the measured state), x_d'
  // and x_d''; observation_size() = 2 n + min(m, 3) + 4 m entries written to `obs`
  void observe(double *obs) const;
  int observation_size() const;
  // one control period with `out` computed at the current instant; false when the run has ended
  // (completed, or diverged: trace().status)
  bool advance(const Output &out);
  // stop the run here with `status` ("interrupted", "failed")
  void end(const std::string &status);
  // the trace (moved out: call once, at the end)
  LoopTrace finish();

 private:
  LoadedModel &model_;
  const LoopSpec &s_;
  std::unique_ptr<Criteria> criteria_;
  std::unique_ptr<Nominal> nominal_;
  std::unique_ptr<Controller> controller_;
  std::unique_ptr<Plant> plant_;
  std::unique_ptr<StickSlipIntegrator> stick_slip_;
  LoopTrace tr_;
  Vector q_, v_, z_, tau_, tau_cmd_, qm_, vm_;
  KinematicsWork kinematics_;
  Rk4Work rk4_;
  Rows commands_;       // the last delay + 1 commands, a ring (row commanded_ % rows is the next)
  long commanded_ = 0;  // commands given so far
  long k_ = 0;
  std::unique_ptr<PartClock> clock_;  // with LoopSpec::profile
  std::unique_ptr<Arena> arena_;      // the law's step's memory (law_in_arena), else none
  std::unique_ptr<Output> out_;       // control()'s, sized here: tau n, z, the signals
  std::string failure_;               // a law's error inside the arena, copied out of it
  // the sizes a law returned, in the error that refuses them (advance and control)
  [[noreturn]] void wrong_sizes(Eigen::Index tau, Eigen::Index z, Eigen::Index signals) const;

 public:
  // with LoopSpec::profile, charge what ran since the last lap to `part` (run_loop's law)
  void lap(LoopPart part) {
    if (clock_) clock_->lap(part);
  }
};

// Whether a run's compiled law takes its step's temporaries from the loop's arena: set by the
// module (bindings.cpp) to "the law and every part it names (robust term, criteria, path) are
// the module's own", since code compiled apart allocates and frees outside the arena's wrappers.
// Unset (nullptr): never.
extern bool (*law_in_arena)(const LoopSpec &spec);

// Whether a run of `spec` takes its law's temporaries from the arena: the allocator is wrapped
// (arena_wrapped) and law_in_arena, set, says the law and its parts allow it.
bool law_runs_in_arena(const LoopSpec &spec);

// Runs the loop; `nominal` is the controller's Pinocchio model (LoopSpec.nominal "pinocchio", else
// unused); `interrupted()` is polled every few hundred steps (Ctrl-C, SIGTERM). With `external`,
// that law replaces the compiled controller (none is built) and the run ends with status
// "failed" where it returns false.
LoopTrace run_loop(LoadedModel &plant, LoadedModel *nominal, const LoopSpec &spec, bool (*interrupted)(),
                   const ExternalLaw *external = nullptr);

// Each compiled component alone, on one state, for the per-component twin tests
// (tests/test_twins.py): the law's output, signals and next state (LoopSpec.law's compute), the
// weighted criterion's gradient on the nominal model and value on the true robot, and the plant's
// q'' (Plant.acceleration, the loads held from t).
struct ControlStep {
  Vector tau, z, signals;
};
ControlStep twin_control(LoadedModel *nominal, const LoopSpec &spec, double t, const Vector &q, const Vector &v,
                         const Vector &z);
Vector twin_criterion_gradient(LoadedModel *nominal, const LoopSpec &spec, const Vector &q);
double twin_criterion_value(LoadedModel &robot, const LoopSpec &spec, const Vector &q);
Vector twin_plant_acceleration(LoadedModel &plant, const LoopSpec &spec, double t, const Vector &q, const Vector &v,
                               const Vector &tau);

// One run of a batch: its own models (each LoadedModel has its own Pinocchio Data) and spec.
struct BatchItem {
  LoadedModel *plant;
  LoadedModel *nominal;  // or nullptr
  const LoopSpec *spec;
};

// Runs the items on `threads` threads (each takes the next item when it finishes one); the
// caller's `interrupted()` is polled every 50 ms on the calling thread and stops every run.
std::vector<LoopTrace> run_batch(const std::vector<BatchItem> &items, int threads, bool (*interrupted)());

}  // namespace nnrobust
