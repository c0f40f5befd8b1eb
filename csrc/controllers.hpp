// The control laws on the C++ side: the twins of nnrobust/controllers (TaskSpaceController's eq. (9)
// with no u_0, the NN compensator or the sliding-mode term; TaskSpacePD), with the desired path of
// nnrobust/trajectories.py.
#pragma once

#include <cmath>
#include <memory>

#include "nominal.hpp"
#include "subtasks/criterion.hpp"

namespace nnrobust {

struct Output {
  Vector tau;
  Vector z;
  double rho_hat = NAN, eps = NAN, z_norm = NAN, damping = 0.0;
  Vector signals;  // a registered law's (LoopSpec.law_signals entries)
};

struct Law;
struct TaskReference;

struct Controller {
  const LoopSpec &s;
  Nominal &nominal;
  Criteria criteria;
  int L = 0;
  // s.law, s.robust and s.path_kind resolved once (an unknown name is refused)
  bool law_pd = false, piecewise = false;
  enum class Robust { none, nn, sliding } robust = Robust::none;
  std::unique_ptr<Law> law;  // a registered law (csrc/laws/), built from spec.law_params

  Controller(const LoopSpec &spec, Nominal &model);
  ~Controller();
  // AdditiveRBFBasis.__call__: [1, exp(-(s_j - c_jk)^2 inv2w2_j) for j, k]
  Vector basis(const Vector &in) const;
  // DampedPseudoInverse.factor: ((J J^T + lambda^2 I)^-1, lambda^2)
  Matrix pinv_factor(const Matrix &J, double &lam2) const;
  // the position path at t: EllipseTrajectory or PiecewisePolynomialPath.__call__ (Horner's rule)
  void path(double t, Vector &pd, Vector &dpd, Vector &ddpd) const;
  // the task state and error at t (PoseTrajectory and tasks.task_error for a pose)
  TaskReference reference(double t, const Vector &q, const Vector &v) const;
  // TaskSpaceController.compute from u_0 on: the torque of eq. (9) with these gains
  Vector eq9_torque(const Vector &q, const Vector &v, const TaskReference &r, const Matrix &J_pinv, const Vector &u0,
                    const Matrix &Kp, const Matrix &Kv, double k);
  // Friction.torque of F-hat (nominal_viscous, nominal_coulomb, coulomb_smoothing) at v
  Vector nominal_friction(const Vector &v) const;
  // the law's torque, signals and next state at t from the measured (q, v) and the state z
  Output compute(double t, const Vector &q, const Vector &v, const Vector &z);
};

}  // namespace nnrobust
