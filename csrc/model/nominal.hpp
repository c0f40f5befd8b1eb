// The controller's nominal models on the C++ side: the interface the controller calls (the twin of
// nnrobust/model/base.py's DynamicsModel) and the twins of nnrobust/model/three_link.py and
// pinocchio_model.py, defined in csrc/model/three_link.cpp and pinocchio_model.cpp.
#pragma once

#include <memory>
#include <vector>

#include "../closed_loop.hpp"
#include "../fields.hpp"
#include "../subtasks/manipulability.hpp"

namespace nnrobust {

using Eigen::Matrix3d;
using Eigen::Vector2d;
using Eigen::Vector3d;
using Matrix23 = Eigen::Matrix<double, 2, 3>;

// nnrobust.model.three_link.ThreeLinkPlanarModel's parameters (its twin_fields).
struct ThreeLinkSpec {
  Eigen::Vector3d beta, p, lengths, gamma;
  Eigen::Vector2d gravity;
  explicit ThreeLinkSpec(const Fields &f)
      : beta(f.vector("beta", 3)), p(f.vector("p", 3)), lengths(f.vector("lengths", 3)),
        gamma(f.vector("gamma", 3)), gravity(f.vector("gravity", 2)) {}
};

// The sines and cosines of q the closed form's M and bias read: computed once per q where many
// models are evaluated at one pose (Slotine-Li's nine unit models, one per column of Y).
struct ThreeLinkTrig {
  double c2, c3, c23, s2, s3, s23;
  Vector3d sin_theta, cos_theta;  // of the links' absolute angles q1, q1 + q2, q1 + q2 + q3
  explicit ThreeLinkTrig(const Vector3d &q);
};

// nnrobust.model.three_link.ThreeLinkPlanarModel: the paper's closed-form nominal model.
struct ThreeLink {
  const ThreeLinkSpec &s;

  Matrix3d mass(const Vector3d &q) const { return mass(ThreeLinkTrig(q)); }
  // V_m(q, v) v + G(q)
  Vector3d bias(const Vector3d &q, const Vector3d &v) const { return bias(ThreeLinkTrig(q), v); }
  Matrix3d mass(const ThreeLinkTrig &trig) const;
  Vector3d bias(const ThreeLinkTrig &trig, const Vector3d &v) const;
  // (x, J, J'q') of ThreeLinkPlanarModel.task_state
  void task_state(const Vector3d &q, const Vector3d &v, Vector2d &x, Matrix23 &J, Vector2d &jdot_v) const;
  // H[:, i, k] = dJ_i/dq_k = tail[:, max(i, k)], tail[:, j] = -sum_{l >= j} l_l (cos, sin) theta_l
  Matrix23 jacobian_tail(const Vector3d &q) const;
};

struct TaskState {
  Vector x, jdot_v;  // x: the frame's position (2 or 3 entries)
  Matrix J;          // m x n
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();  // the frame's orientation (pose tasks)
  Matrix J6;         // the whole 6 x n frame Jacobian, world-aligned (Pinocchio models only)
};


struct Nominal {
  virtual ~Nominal() = default;
  virtual TaskState task_state(const Vector &q, const Vector &v) = 0;
  virtual Vector inverse_dynamics(const Vector &q, const Vector &v, const Vector &a) = 0;  // M a + N
  virtual Vector gravity(const Vector &q) = 0;
  // d det(J J^T)/dq at the q of `ts` (the task state just computed)
  virtual Vector det_gradient(const Vector &q, const TaskState &ts) = 0;
  // chain_points (rows: joint origins, then the task frame) and chain_jacobians (3 x n each)
  virtual void chain(const Vector &q, Matrix &points, std::vector<Matrix> &jacobians) = 0;
};

struct ClosedFormNominal : Nominal {
  const ThreeLinkSpec spec;
  ThreeLink model{spec};
  explicit ClosedFormNominal(const Fields &f) : spec(f) {}
  TaskState task_state(const Vector &q, const Vector &v) override;
  Vector inverse_dynamics(const Vector &q, const Vector &v, const Vector &a) override;
  Vector gravity(const Vector &q) override;
  Vector det_gradient(const Vector &q, const TaskState &ts) override;
  void chain(const Vector &q, Matrix &points, std::vector<Matrix> &jacobians) override;
};

// PinocchioModel: task_state, inverse_dynamics (RNEA), gravity, det_jjt_gradient (O(n))
struct PinocchioNominal : Nominal {
  LoadedModel &m;
  int rows;
  PinocchioNominal(LoadedModel &model, int task_rows) : m(model), rows(task_rows) {}
  TaskState task_state(const Vector &q, const Vector &v) override;
  Vector inverse_dynamics(const Vector &q, const Vector &v, const Vector &a) override;
  Vector gravity(const Vector &q) override;
  Vector det_gradient(const Vector &q, const TaskState &ts) override;
  void chain(const Vector &q, Matrix &points, std::vector<Matrix> &jacobians) override;
};

// The controller's nominal model LoopSpec.nominal names: the closed form (from nominal_params) or
// the Pinocchio model `nominal_model` ("pinocchio"); an unknown name is refused.
std::unique_ptr<Nominal> make_nominal(const LoopSpec &s, LoadedModel *nominal_model);

}  // namespace nnrobust
