// A Pinocchio nominal model: the twin of nnrobust/model/pinocchio_model.py (PinocchioModel's
// task state, RNEA, gravity, the O(n) manipulability gradient and the chain), behind the Nominal
// interface (nominal.hpp).
#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>

#include "nominal.hpp"
#include "../pin_calls.hpp"

namespace nnrobust {

std::unique_ptr<Nominal> make_nominal(const LoopSpec &s, LoadedModel *nominal_model) {
  if (s.nominal == "closed-form")
    return std::make_unique<ClosedFormNominal>(Fields{"LoopSpec.nominal_params: the closed form", s.nominal_params});
  if (s.nominal != "pinocchio") throw std::invalid_argument("LoopSpec.nominal: unknown nominal model " + s.nominal);
  if (nominal_model == nullptr) throw std::invalid_argument("the nominal model 'pinocchio' needs its model");
  return std::make_unique<PinocchioNominal>(*nominal_model, s.m);
}

TaskState PinocchioNominal::task_state(const Vector &q, const Vector &v) {
  pin::forwardKinematics(m.model, m.data, q, v, Vector::Zero(m.model.nv));
  pin::computeJointJacobians(m.model, m.data);
  const auto &placement = pin::updateFramePlacement(m.model, m.data, m.frame);
  const auto acc = pin::getFrameClassicalAcceleration(m.model, m.data, m.frame, pinocchio::LOCAL_WORLD_ALIGNED);
  TaskState ts;
  pin::Matrix6x J6 = pin::Matrix6x::Zero(6, m.model.nv);
  pin::getFrameJacobian(m.model, m.data, m.frame, pinocchio::LOCAL_WORLD_ALIGNED, J6);
  ts.J6 = J6;
  ts.x = placement.translation().head(std::min(rows, 3));
  ts.jdot_v = acc.toVector().head(rows);
  ts.J = ts.J6.topRows(rows);
  ts.R = placement.rotation();
  return ts;
}

Vector PinocchioNominal::inverse_dynamics(const Vector &q, const Vector &v, const Vector &a) {
  return pin::rnea(m.model, m.data, q, v, a);
}

Vector PinocchioNominal::gravity(const Vector &q) { return pin::computeGeneralizedGravity(m.model, m.data, q); }

// grad_k = 2 (<u_k, P_k> + <w_k, S_k>), docs/equations.md "Manipulability gradient", from the
// frame Jacobian the task state already holds (no second kinematics pass)
Vector PinocchioNominal::det_gradient(const Vector &, const TaskState &ts) {
  const Matrix &J6 = ts.J6;
  const Matrix &J = ts.J;
  Matrix W6 = Matrix::Zero(6, J6.cols());
  W6.topRows(rows) = adjugate_small(J * J.transpose()) * J;
  const int n = static_cast<int>(J6.cols());
  Vector grad(n);
  Vector3d prefix = Vector3d::Zero(), suffix = Vector3d::Zero();
  std::vector<Vector3d> after(n);
  for (int l = 0; l < n; ++l) {
    const Vector3d u = J6.col(l).head<3>(), w = J6.col(l).tail<3>();
    after[l] = u.cross(Vector3d(W6.col(l).head<3>())) + w.cross(Vector3d(W6.col(l).tail<3>()));
  }
  std::vector<Vector3d> suffixes(n);
  for (int l = n - 1; l >= 0; --l) {
    suffix += after[l];
    suffixes[l] = suffix;
  }
  for (int k = 0; k < n; ++k) {
    const Vector3d u = J6.col(k).head<3>(), w = J6.col(k).tail<3>();
    grad[k] = 2.0 * (u.dot(prefix) + w.dot(suffixes[k]));
    prefix += Vector3d(W6.col(k).head<3>()).cross(w);
  }
  return grad;
}

// PinocchioModel.chain_points / chain_jacobians
void PinocchioNominal::chain(const Vector &q, Matrix &points, std::vector<Matrix> &jacobians) {
  const int joints = m.model.njoints - 1, n = m.model.nv;
  pin::computeJointJacobians(m.model, m.data, q);
  pin::updateFramePlacement(m.model, m.data, m.frame);
  points.resize(joints + 1, 3);
  jacobians.assign(joints + 1, Matrix::Zero(3, n));
  pin::Matrix6x J = pin::Matrix6x::Zero(6, n);
  for (int j = 1; j <= joints; ++j) {
    points.row(j - 1) = m.data.oMi[j].translation().transpose();
    J.setZero();
    pin::getJointJacobian(m.model, m.data, j, pinocchio::LOCAL_WORLD_ALIGNED, J);
    jacobians[j - 1] = J.topRows(3);
  }
  points.row(joints) = m.data.oMf[m.frame].translation().transpose();
  J.setZero();
  pin::getFrameJacobian(m.model, m.data, m.frame, pinocchio::LOCAL_WORLD_ALIGNED, J);
  jacobians[joints] = J.topRows(3);
}

}  // namespace nnrobust
