// The compiled closed loop: the C++ twin of nnrobust.simulation.simulate for the components that
// have a compiled twin (docs/compiled.md). Every formula mirrors its Python reference, named in
// the comments; tests/test_compiled.py holds the two equal.
#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "model.hpp"

namespace nnrobust {

inline double sign(double x) { return (x > 0) - (x < 0); }  // numpy.sign

// Row-major: a step reads or writes one contiguous row of each per-step array (a column-major
// steps x n array would make every recorded value a cache miss, which dominated the step for
// long chains).
using Rows = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// nnrobust.model.three_link.ThreeLinkPlanarModel: the paper's closed-form nominal model.
struct ThreeLinkSpec {
  Eigen::Vector3d beta, p, lengths, gamma;
  Eigen::Vector2d gravity = Eigen::Vector2d::Zero();
};

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
  // plant (nnrobust.plant): friction, sinusoidal disturbance, saturation, stops, sensor, delay
  Vector viscous, coulomb, static_friction;  // static_friction: F_s (> 0: stick-slip joints)
  Matrix dist_amplitude, dist_phase;  // n x K
  Vector dist_omega;                  // K
  Vector torque_limit;                // n (inf: none); empty: ideal actuators
  bool stops = false;
  Vector stop_lower, stop_upper, stop_stiffness, stop_ring;  // ring: sqrt(K (M^-1)_ii) at q0 [rad/s]
  double stop_alpha = 0.0;
  // [[plant.loads]] (nnrobust/plant/loads.py, Plant.begin_period), switched at control instants:
  // joint torque pulses u over [start, end), tool wrenches w (world axes at the task frame) over
  // [start, end), payload changes at start; payload_inertia holds the dynamic parameters
  // (pin.Inertia.toDynamicParameters) of the joint payload_joint after each change, then before any
  Vector pulse_start, pulse_end, wrench_start, wrench_end, payload_start;  // P, P, W, W, C
  Matrix pulse_torque, wrench;                                            // n x P, 6 x W
  Matrix payload_inertia;                                                 // 10 x (C + 1)
  int payload_joint = 0;
  Vector position_noise, velocity_noise, resolution;  // n (zeros: ideal)
  Rows noise_q, noise_v;                              // steps x n standard normal draws (or empty)
  int delay = 0;
  // plant.engine = "mujoco" (nnrobust/plant/mujoco_engine.py, MujocoPlant.advance): MuJoCo steps the
  // plant. The addresses of its mj_step, mjModel and mjData and of qpos, qvel, ctrl and qfrc_applied
  // inside the data (the caller keeps them alive for the run, and resets the state to q0, v0);
  // joint i sits at qpos[mj_qpos_index[i]], qvel[mj_dof_index[i]] and ctrl[i]. No MuJoCo header is
  // needed: mj_step(const mjModel*, mjData*) is the only call.
  std::uintptr_t mj_step = 0, mj_model = 0, mj_data = 0;
  std::uintptr_t mj_qpos = 0, mj_qvel = 0, mj_ctrl = 0, mj_qfrc_applied = 0;
  std::vector<int> mj_qpos_index, mj_dof_index;
  // nominal model: "closed-form" (ThreeLinkSpec) or "pinocchio" (a second LoadedModel)
  std::string nominal_kind = "closed-form";
  ThreeLinkSpec nominal;
  int m = 2;  // task rows: 2 (planar: x, y), 3 (position) or 6 (pose: position, then rotation)
  Vector nominal_viscous, nominal_coulomb;
  double coulomb_smoothing = unset;
  // the desired motion (nnrobust/trajectories/): the position path registered under `path`
  // (csrc/trajectories/) with its fields by name (its Python class's twin_fields), and for a pose
  // task (m = 6) PoseTrajectory's orientation fields
  std::string path;
  std::map<std::string, Matrix> path_params;
  bool pose = false;
  std::map<std::string, Matrix> pose_params;
  // the law registered under `law` (csrc/controllers/, csrc/laws/; "external": the hybrid loop's
  // Python law) with its fields by name (Law.twin_values) and its number of signals; the eq. (9)
  // law's robust term registered under `robust` ("" for u_0 = 0) with its fields
  std::string law;
  std::map<std::string, Matrix> law_params;
  int law_signals = 0;
  std::string robust;
  std::map<std::string, Matrix> robust_params;
  // WeightedCriteria: each criterion's registered name (csrc/subtasks/), its fields by name (its
  // Python declaration's twin_fields) and its weight (already scaled to sum to C)
  std::vector<std::string> criteria;
  std::vector<std::map<std::string, Matrix>> criterion_params;
  Vector criterion_weights;
  double pinv_threshold = unset, pinv_max_damping = unset;
  Vector z0;
};

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
};

// A control law without a compiled twin (the hybrid loop: a Python controller's compute), called
// once per control period with the measured (q, q') and the state z; it fills tau (n entries)
// and z_next (z's size) and returns false to stop the run (the caller keeps the error).
using ExternalLaw = std::function<bool(double t, const Vector &q, const Vector &v, const Vector &z, Vector &tau,
                                       Vector &z_next)>;

// Runs the loop; `nominal` is the controller's Pinocchio model (nominal_kind "pinocchio", else
// unused); `interrupted()` is polled every few hundred steps (Ctrl-C, SIGTERM). With `external`,
// that law replaces the compiled controller (spec.law "external") and the run ends with status
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
