// The closed-form nominal model: the twin of nnrobust/model/three_link.py (ThreeLinkPlanarModel),
// the paper's matrices with the errata's corrections, behind the Nominal interface (nominal.hpp).
#include <cmath>

#include "nominal.hpp"

namespace nnrobust {

ThreeLinkTrig::ThreeLinkTrig(const Vector3d &q)
    : c2(std::cos(q[1])), c3(std::cos(q[2])), c23(std::cos(q[1] + q[2])), s2(std::sin(q[1])), s3(std::sin(q[2])),
      s23(std::sin(q[1] + q[2])) {
  const Vector3d theta(q[0], q[0] + q[1], q[0] + q[1] + q[2]);
  for (int j = 0; j < 3; ++j) {
    sin_theta[j] = std::sin(theta[j]);
    cos_theta[j] = std::cos(theta[j]);
  }
}

Matrix3d ThreeLink::mass(const ThreeLinkTrig &trig) const {
  const double c2 = trig.c2, c3 = trig.c3, c23 = trig.c23;
  const double m11 = s.beta[0] + 2 * s.p[0] * c2 + 2 * s.p[1] * c23 + 2 * s.p[2] * c3;
  const double m12 = s.beta[1] + s.p[0] * c2 + s.p[1] * c23 + 2 * s.p[2] * c3;
  const double m13 = s.beta[2] + s.p[1] * c23 + s.p[2] * c3;
  const double m22 = s.beta[1] + 2 * s.p[2] * c3;
  const double m23 = s.beta[2] + s.p[2] * c3;
  Matrix3d M;
  M << m11, m12, m13, m12, m22, m23, m13, m23, s.beta[2];
  return M;
}

Vector3d ThreeLink::bias(const ThreeLinkTrig &trig, const Vector3d &v) const {
  const double s2 = trig.s2, s3 = trig.s3, s23 = trig.s23;
  const double a = s.p[0] * s2 + s.p[1] * s23, b = s.p[1] * s23 + s.p[2] * s3, c = s.p[2] * s3;
  const double v1 = v[0], v2 = v[1], v3 = v[2];
  Matrix3d V;
  V << -a * v2 - b * v3, -a * (v1 + v2) - b * v3, -b * (v1 + v2 + v3),
      a * v1 - c * v3, -c * v3, -c * (v1 + v2 + v3),
      b * v1 + c * v2, c * (v1 + v2), 0.0;
  Vector3d dU;
  for (int j = 0; j < 3; ++j)
    dU[j] = s.gamma[j] * (s.gravity[0] * trig.sin_theta[j] - s.gravity[1] * trig.cos_theta[j]);
  Vector3d G(dU[0] + dU[1] + dU[2], dU[1] + dU[2], dU[2]);
  return V * v + G;
}

void ThreeLink::task_state(const Vector3d &q, const Vector3d &v, Vector2d &x, Matrix23 &J, Vector2d &jdot_v) const {
  Vector3d theta(q[0], q[0] + q[1], q[0] + q[1] + q[2]);
  Vector3d w(v[0], v[0] + v[1], v[0] + v[1] + v[2]);
  Vector3d c = theta.array().cos(), sn = theta.array().sin();
  x << s.lengths.dot(c), s.lengths.dot(sn);
  Eigen::Matrix<double, 2, 3> cols;
  cols.row(0) = -(s.lengths.array() * sn.array()).matrix().transpose();
  cols.row(1) = (s.lengths.array() * c.array()).matrix().transpose();
  J.col(2) = cols.col(2);
  J.col(1) = cols.col(2) + cols.col(1);
  J.col(0) = J.col(1) + cols.col(0);
  Vector3d lw2 = (s.lengths.array() * w.array().square()).matrix();
  jdot_v << -c.dot(lw2), -sn.dot(lw2);
}

Matrix23 ThreeLink::jacobian_tail(const Vector3d &q) const {
  Vector3d theta(q[0], q[0] + q[1], q[0] + q[1] + q[2]);
  Eigen::Matrix<double, 2, 3> terms, tail;
  for (int j = 0; j < 3; ++j) terms.col(j) << -s.lengths[j] * std::cos(theta[j]), -s.lengths[j] * std::sin(theta[j]);
  tail.col(2) = terms.col(2);
  tail.col(1) = terms.col(2) + terms.col(1);
  tail.col(0) = tail.col(1) + terms.col(0);
  return tail;
}

// ClosedFormNominal: ThreeLink behind the Nominal interface
TaskState ClosedFormNominal::task_state(const Vector &q, const Vector &v) {
  Vector2d x, jdot_v;
  Matrix23 J;
  model.task_state(q, v, x, J, jdot_v);
  return {x, jdot_v, J};
}

Vector ClosedFormNominal::inverse_dynamics(const Vector &q, const Vector &v, const Vector &a) {
  return model.mass(q) * Vector3d(a) + model.bias(q, v);
}

Vector ClosedFormNominal::gravity(const Vector &q) { return model.bias(q, Vector3d::Zero()); }

// einsum("ij,jlk,il->k", adj, H, J) x 2 with H[:, l, k] = tail[:, max(l, k)]
Vector ClosedFormNominal::det_gradient(const Vector &q, const TaskState &ts) {
  const Matrix &J = ts.J;
  const Matrix23 tail = model.jacobian_tail(q);
  const Matrix adj = adjugate_small(J * J.transpose());
  Vector grad = Vector::Zero(3);
  for (int k = 0; k < 3; ++k) {
    double sum = 0.0;
    for (int i = 0; i < 2; ++i)
      for (int j = 0; j < 2; ++j)
        for (int l = 0; l < 3; ++l) sum += adj(i, j) * tail(j, std::max(l, k)) * J(i, l);
    grad[k] = 2.0 * sum;
  }
  return grad;
}

// ThreeLinkPlanarModel.chain_points / chain_jacobians
void ClosedFormNominal::chain(const Vector &q, Matrix &points, std::vector<Matrix> &jacobians) {
  const Vector3d theta(q[0], q[0] + q[1], q[0] + q[1] + q[2]);
  points = Matrix::Zero(4, 3);
  jacobians.assign(4, Matrix::Zero(3, 3));
  for (int j = 1; j < 4; ++j) {
    points.row(j) = points.row(j - 1);
    points(j, 0) += model.s.lengths[j - 1] * std::cos(theta[j - 1]);
    points(j, 1) += model.s.lengths[j - 1] * std::sin(theta[j - 1]);
    for (int k = 0; k < j; ++k)
      for (int i = k; i < j; ++i) {
        jacobians[j](0, k) += -model.s.lengths[i] * std::sin(theta[i]);
        jacobians[j](1, k) += model.s.lengths[i] * std::cos(theta[i]);
      }
  }
}

}  // namespace nnrobust
