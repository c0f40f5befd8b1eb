// The parts every control law on the C++ side shares (the twins of nnrobust/controllers/ and
// nnrobust/trajectories/): the desired motion and the task error, the damped pseudo-inverse, the
// torque of eq. (9) and the nominal friction. The law itself is a registered component
// (csrc/controllers/, csrc/controllers/laws/) named by LoopSpec.law and built from LoopSpec.law_params.
#pragma once

#include <cmath>
#include <memory>
#include <optional>

#include "model/nominal.hpp"
#include "plant/friction.hpp"
#include "subtasks/criterion.hpp"
#include "trajectories/trajectory.hpp"

namespace nnrobust {

struct Output {
  Vector tau;
  Vector z;
  Vector signals;  // the law's, in its Python twin's signal_names order (LoopSpec.law_signals entries)
};

struct Law;
struct TaskReference;

struct NNROBUST_API Controller {
  const LoopSpec &s;
  Nominal &nominal;
  Criteria criteria;
  std::unique_ptr<Path> path;               // LoopSpec.path, from path_params
  std::optional<Orientation> orientation;   // a pose task's (LoopSpec.pose_params)
  std::unique_ptr<Law> law;                 // LoopSpec.law, from law_params
  Friction friction;                        // the controller's F-hat (LoopSpec.nominal_friction)

  // every name resolved here, once: an unknown one is refused (std::invalid_argument)
  Controller(const LoopSpec &spec, Nominal &model);
  ~Controller();
  // DampedPseudoInverse.factor: ((J J^T + lambda^2 I)^-1, lambda^2)
  Matrix pinv_factor(const Matrix &J, double &lam2) const;
  // the task state and error at t (PoseTrajectory and tasks.task_error for a pose)
  TaskReference reference(double t, const Vector &q, const Vector &v) const;
  // reference(t, q, v), kept for the law's next compute at the same (t, q, v): a learning
  // environment observes the reference the law then computes again (SteppedLoop::observe)
  const TaskReference &reference_kept(double t, const Vector &q, const Vector &v) const;
  // TaskSpaceController.compute from u_0 on: the torque of eq. (9) with these gains
  Vector eq9_torque(const Vector &q, const Vector &v, const TaskReference &r, const Matrix &J_pinv, const Vector &u0,
                    const Matrix &Kp, const Matrix &Kv, double k);
  // Friction.torque of F-hat (LoopSpec.nominal_friction) at v
  Vector nominal_friction(const Vector &v) const;
  // the law's torque, signals and next state at t from the measured (q, v) and the state z
  Output compute(double t, const Vector &q, const Vector &v, const Vector &z);

 private:
  // what reference_kept computed last, and where: taken by the next reference call there
  mutable std::unique_ptr<TaskReference> kept_;  // one slot, reused
  mutable bool kept_valid_ = false;
  mutable double kept_t_ = 0.0;
  mutable Vector kept_q_, kept_v_;
};

}  // namespace nnrobust
