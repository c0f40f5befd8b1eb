#include "closed_loop.hpp"
#include "stick_slip.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <deque>
#include <limits>
#include <memory>
#include <thread>

#include <Eigen/Eigenvalues>
#include <pinocchio/spatial/explog.hpp>

#include "pin_calls.hpp"

namespace nnrobust {
namespace {

using Eigen::Matrix2d;
using Eigen::Matrix3d;
using Eigen::Vector2d;
using Eigen::Vector3d;

// ---- the closed-form nominal model (nnrobust/model/three_link.py) ------------------------------
struct ThreeLink {
  const ThreeLinkSpec &s;

  Matrix3d mass(const Vector3d &q) const {
    const double c2 = std::cos(q[1]), c3 = std::cos(q[2]), c23 = std::cos(q[1] + q[2]);
    const double m11 = s.beta[0] + 2 * s.p[0] * c2 + 2 * s.p[1] * c23 + 2 * s.p[2] * c3;
    const double m12 = s.beta[1] + s.p[0] * c2 + s.p[1] * c23 + 2 * s.p[2] * c3;
    const double m13 = s.beta[2] + s.p[1] * c23 + s.p[2] * c3;
    const double m22 = s.beta[1] + 2 * s.p[2] * c3;
    const double m23 = s.beta[2] + s.p[2] * c3;
    Matrix3d M;
    M << m11, m12, m13, m12, m22, m23, m13, m23, s.beta[2];
    return M;
  }

  Vector3d bias(const Vector3d &q, const Vector3d &v) const {  // V_m(q, v) v + G(q)
    const double s2 = std::sin(q[1]), s3 = std::sin(q[2]), s23 = std::sin(q[1] + q[2]);
    const double a = s.p[0] * s2 + s.p[1] * s23, b = s.p[1] * s23 + s.p[2] * s3, c = s.p[2] * s3;
    const double v1 = v[0], v2 = v[1], v3 = v[2];
    Matrix3d V;
    V << -a * v2 - b * v3, -a * (v1 + v2) - b * v3, -b * (v1 + v2 + v3),
        a * v1 - c * v3, -c * v3, -c * (v1 + v2 + v3),
        b * v1 + c * v2, c * (v1 + v2), 0.0;
    Vector3d theta(q[0], q[0] + q[1], q[0] + q[1] + q[2]);
    Vector3d dU;
    for (int j = 0; j < 3; ++j)
      dU[j] = s.gamma[j] * (s.gravity[0] * std::sin(theta[j]) - s.gravity[1] * std::cos(theta[j]));
    Vector3d G(dU[0] + dU[1] + dU[2], dU[1] + dU[2], dU[2]);
    return V * v + G;
  }

  // (x, J, J'q') of ThreeLinkPlanarModel.task_state
  void task_state(const Vector3d &q, const Vector3d &v, Vector2d &x, Eigen::Matrix<double, 2, 3> &J,
                  Vector2d &jdot_v) const {
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

  // H[:, i, k] = dJ_i/dq_k = tail[:, max(i, k)], tail[:, j] = -sum_{l >= j} l_l (cos, sin) theta_l
  Eigen::Matrix<double, 2, 3> jacobian_tail(const Vector3d &q) const {
    Vector3d theta(q[0], q[0] + q[1], q[0] + q[1] + q[2]);
    Eigen::Matrix<double, 2, 3> terms, tail;
    for (int j = 0; j < 3; ++j) terms.col(j) << -s.lengths[j] * std::cos(theta[j]), -s.lengths[j] * std::sin(theta[j]);
    tail.col(2) = terms.col(2);
    tail.col(1) = terms.col(2) + terms.col(1);
    tail.col(0) = tail.col(1) + terms.col(0);
    return tail;
  }
};

// ---- the nominal models (nnrobust/model) ---------------------------------------------------------
struct TaskState {
  Vector x, jdot_v;  // x: the frame's position (2 or 3 entries)
  Matrix J;          // m x n
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();  // the frame's orientation (pose tasks)
  Matrix J6;         // the whole 6 x n frame Jacobian, world-aligned (Pinocchio models only)
};

// det and adjugate of J J^T, shared by both nominal models and the recording
double det_small(const Matrix &A) {  // manipulability.det: closed form for m <= 3, else LU
  if (A.rows() == 1) return A(0, 0);
  if (A.rows() == 2) return A(0, 0) * A(1, 1) - A(0, 1) * A(1, 0);
  if (A.rows() > 3) return A.determinant();
  const Vector3d a0 = A.col(0), a1 = A.col(1), a2 = A.col(2);
  return a0.dot(a1.cross(a2));
}

Matrix adjugate_small(const Matrix &A) {  // manipulability.adjugate for m <= 3
  Matrix adj(A.rows(), A.cols());
  if (A.rows() == 1) {
    adj(0, 0) = 1.0;
  } else if (A.rows() == 2) {
    adj << A(1, 1), -A(0, 1), -A(1, 0), A(0, 0);
  } else {
    const Vector3d a0 = A.col(0), a1 = A.col(1), a2 = A.col(2);
    adj.row(0) = a1.cross(a2).transpose();
    adj.row(1) = a2.cross(a0).transpose();
    adj.row(2) = a0.cross(a1).transpose();
  }
  return adj;
}

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
  ThreeLink model;
  explicit ClosedFormNominal(const ThreeLinkSpec &s) : model{s} {}

  TaskState task_state(const Vector &q, const Vector &v) override {
    Vector2d x, jdot_v;
    Eigen::Matrix<double, 2, 3> J;
    model.task_state(q, v, x, J, jdot_v);
    return {x, jdot_v, J};
  }
  Vector inverse_dynamics(const Vector &q, const Vector &v, const Vector &a) override {
    return model.mass(q) * Vector3d(a) + model.bias(q, v);
  }
  Vector gravity(const Vector &q) override { return model.bias(q, Vector3d::Zero()); }
  // einsum("ij,jlk,il->k", adj, H, J) x 2 with H[:, l, k] = tail[:, max(l, k)]
  Vector det_gradient(const Vector &q, const TaskState &ts) override {
    const Matrix &J = ts.J;
    const Eigen::Matrix<double, 2, 3> tail = model.jacobian_tail(q);
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
  void chain(const Vector &q, Matrix &points, std::vector<Matrix> &jacobians) override {
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
};

// PinocchioModel: task_state, inverse_dynamics (RNEA), gravity, det_jjt_gradient (O(n))
struct PinocchioNominal : Nominal {
  LoadedModel &m;
  int rows;
  PinocchioNominal(LoadedModel &model, int task_rows) : m(model), rows(task_rows) {}

  TaskState task_state(const Vector &q, const Vector &v) override {
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
  Vector inverse_dynamics(const Vector &q, const Vector &v, const Vector &a) override {
    return pin::rnea(m.model, m.data, q, v, a);
  }
  Vector gravity(const Vector &q) override { return pin::computeGeneralizedGravity(m.model, m.data, q); }
  // grad_k = 2 (<u_k, P_k> + <w_k, S_k>), docs/equations.md "Manipulability gradient", from the
  // frame Jacobian the task state already holds (no second kinematics pass)
  Vector det_gradient(const Vector &, const TaskState &ts) override {
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
  void chain(const Vector &q, Matrix &points, std::vector<Matrix> &jacobians) override {
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
};

// SphereObstacles._pairs for every (segment, obstacle): t, the unit normal and the clearance d
struct ObstaclePair {
  int segment;
  double t, depth;
  Vector3d normal;
};

std::vector<ObstaclePair> obstacle_pairs(const LoopSpec &s, const Matrix &points) {
  std::vector<ObstaclePair> pairs;
  for (int seg = 0; seg + 1 < points.rows(); ++seg) {
    const Vector3d a = points.row(seg).transpose(), b = points.row(seg + 1).transpose(), ab = b - a;
    const double length2 = std::max(ab.squaredNorm(), 1e-300);
    for (int o = 0; o < s.obstacle_centers.rows(); ++o) {
      const Vector3d c = s.obstacle_centers.row(o).transpose();
      const double t = std::clamp((c - a).dot(ab) / length2, 0.0, 1.0);
      const Vector3d gap = c - (a + t * ab);
      const double dist = std::max(gap.norm(), 1e-12);
      const double d = dist - s.obstacle_radii[o] - s.link_radius;
      pairs.push_back({seg, t, std::max(0.0, s.obstacle_influence - d), gap / dist});
    }
  }
  return pairs;
}

// ---- the criteria (nnrobust/subtasks) ------------------------------------------------------------
struct Criteria {
  const LoopSpec &s;

  // JointLimitAvoidance._barrier: (b, b') with the linear continuation outside the knots; a joint
  // without limits (a continuous joint) has b = 1, b' = 0
  void barrier(const Vector &q, Vector &b, Vector &db) const {
    const Vector span = s.limit_upper - s.limit_lower;
    b.resize(q.size());
    db.resize(q.size());
    for (int i = 0; i < q.size(); ++i) {
      if (!std::isfinite(span[i])) {
        b[i] = 1.0;
        db[i] = 0.0;
        continue;
      }
      const double lo = s.limit_lower[i] + s.limit_margin * span[i], hi = s.limit_upper[i] - s.limit_margin * span[i];
      const double knot = std::clamp(q[i], lo, hi);
      const double g = (s.limit_upper[i] - knot) * (knot - s.limit_lower[i]);
      const double bi = span[i] * span[i] / (4 * g);
      db[i] = -span[i] * span[i] * (s.limit_upper[i] + s.limit_lower[i] - 2 * knot) / (4 * g * g);
      b[i] = bi + db[i] * (q[i] - knot);
    }
  }

  // JointCentering: (q - c) / (u - l), c the mid-range; 0 for a joint without limits
  Vector centered(const Vector &q) const {
    Vector c(q.size());
    for (int i = 0; i < q.size(); ++i) {
      const double span = s.limit_upper[i] - s.limit_lower[i];
      c[i] = std::isfinite(span) ? (q[i] - 0.5 * (s.limit_lower[i] + s.limit_upper[i])) / span : 0.0;
    }
    return c;
  }

  // WeightedCriteria.gradient on the nominal model (ts: its task state at q)
  Vector gradient(Nominal &model, const Vector &q, const TaskState &ts) const {
    const Matrix &J = ts.J;
    const int n = static_cast<int>(q.size());
    Vector grad = Vector::Zero(n);
    bool have_det = false;
    double det = 0.0;
    Vector ddet;
    auto det_terms = [&]() {
      if (!have_det) {
        det = det_small(J * J.transpose());
        ddet = model.det_gradient(q, ts);
        have_det = true;
      }
    };
    for (size_t c = 0; c < s.criteria.size(); ++c) {
      const std::string &kind = s.criteria[c];
      Vector g;
      if (kind == "paper" || kind == "half_det") {
        det_terms();
        g = 0.5 * ddet;
        if (kind == "paper") g += -s.smoothness.dot(q) * s.smoothness;
      } else if (kind == "manipulability") {
        det_terms();
        g = det <= 1e-300 ? Vector(Vector::Zero(n)) : Vector(ddet / (2.0 * std::sqrt(det)));
      } else if (kind == "joint_limits") {
        Vector b, db;
        barrier(q, b, db);
        g = -db / static_cast<double>(n);
      } else if (kind == "joint_smoothness") {
        g = -s.smoothing_coefficients.dot(q) * s.smoothing_coefficients;
      } else if (kind == "obstacles") {  // sum over pairs of depth * (-n^T ((1 - t) J_a + t J_b))
        Matrix points;
        std::vector<Matrix> jacobians;
        model.chain(q, points, jacobians);
        g = Vector::Zero(n);
        for (const ObstaclePair &p : obstacle_pairs(s, points))
          if (p.depth > 0.0)
            g += -(p.depth * (1 - p.t)) * (jacobians[p.segment].transpose() * p.normal) -
                 (p.depth * p.t) * (jacobians[p.segment + 1].transpose() * p.normal);
      } else {  // joint_centering: -(q - c) / (n (u - l)^2)
        g = -centered(q).cwiseQuotient(s.limit_upper - s.limit_lower) / static_cast<double>(n);
      }
      grad += s.criterion_weights[c] * g;
    }
    return grad;
  }

  // WeightedCriteria.value on the true robot (J: its task Jacobian at q, points: its chain)
  double value(const Vector &q, const Matrix &J, const Matrix &points) const {
    const int n = static_cast<int>(q.size());
    const double det = det_small(J * J.transpose());
    double h = 0.0;
    for (size_t c = 0; c < s.criteria.size(); ++c) {
      const std::string &kind = s.criteria[c];
      double v;
      if (kind == "paper") {
        const double cq = s.smoothness.dot(q);
        v = 0.5 * det + (-0.5 * cq * cq);
      } else if (kind == "half_det") {
        v = 0.5 * det;
      } else if (kind == "manipulability") {
        v = std::sqrt(std::max(det, 0.0));
      } else if (kind == "joint_limits") {
        Vector b, db;
        barrier(q, b, db);
        v = -b.mean();
      } else if (kind == "joint_smoothness") {
        const double cq = s.smoothing_coefficients.dot(q);
        v = -0.5 * cq * cq;
      } else if (kind == "obstacles") {
        v = 0.0;
        for (const ObstaclePair &p : obstacle_pairs(s, points)) v += p.depth * p.depth;
        v *= -0.5;
      } else {  // joint_centering: -(1/(2n)) sum ((q - c) / (u - l))^2
        v = -0.5 * centered(q).squaredNorm() / static_cast<double>(n);
      }
      h += s.criterion_weights[c] * v;
    }
    return h;
  }
};

// ---- the controller (nnrobust/controllers) ------------------------------------------------------
struct Output {
  Vector tau;
  Vector z;
  double rho_hat = NAN, eps = NAN, z_norm = NAN, damping = 0.0;
};

struct Controller {
  const LoopSpec &s;
  Nominal &nominal;
  Criteria criteria;
  int L = 0;

  Controller(const LoopSpec &spec, Nominal &model) : s(spec), nominal(model), criteria{spec} {
    L = static_cast<int>(spec.basis_bias) + static_cast<int>(spec.basis_centers.size());
  }

  // AdditiveRBFBasis.__call__: [1, exp(-(s_j - c_jk)^2 inv2w2_j) for j, k]
  Vector basis(const Vector &in) const {
    Vector phi(L);
    int i = 0;
    if (s.basis_bias) phi[i++] = 1.0;
    for (int j = 0; j < s.basis_centers.rows(); ++j)
      for (int c = 0; c < s.basis_centers.cols(); ++c) {
        const double d = in[j] - s.basis_centers(j, c);
        phi[i++] = std::exp(-(d * d) * s.basis_inv2w2[j]);
      }
    return phi;
  }

  // DampedPseudoInverse.factor: ((J J^T + lambda^2 I)^-1, lambda^2)
  Matrix pinv_factor(const Matrix &J, double &lam2) const {
    const Matrix JJt = J * J.transpose();
    const double sigma_min_sq =
        std::max(Eigen::SelfAdjointEigenSolver<Matrix>(JJt, Eigen::EigenvaluesOnly).eigenvalues()[0], 0.0);
    const double thr_sq = s.pinv_threshold * s.pinv_threshold;
    lam2 = sigma_min_sq >= thr_sq ? 0.0 : s.pinv_max_damping * s.pinv_max_damping * (1.0 - sigma_min_sq / thr_sq);
    return (JJt + lam2 * Matrix::Identity(J.rows(), J.rows())).inverse();
  }

  // the position path at t: EllipseTrajectory or PiecewisePolynomialPath.__call__ (Horner's rule)
  void path(double t, Vector &pd, Vector &dpd, Vector &ddpd) const {
    if (s.path_kind != "piecewise") {
      const double ph = s.omega * t + s.phase, cw = std::cos(ph), sw = std::sin(ph);
      pd = s.center + s.axis_a * cw + s.axis_b * sw;
      dpd = s.omega * (-s.axis_a * sw + s.axis_b * cw);
      ddpd = -(s.omega * s.omega) * (s.axis_a * cw + s.axis_b * sw);
      return;
    }
    const Vector &b = s.path_breaks;
    const int pieces = static_cast<int>(b.size()) - 1, order = static_cast<int>(s.path_coefficients.rows()) / pieces;
    int p = 0;
    double h = 0.0;
    bool moving = false;
    if (t >= b[pieces]) {
      p = pieces - 1;
      h = b[pieces] - b[p];
    } else if (t > b[0]) {
      p = static_cast<int>(std::upper_bound(b.data(), b.data() + b.size(), t) - b.data()) - 1;
      h = t - b[p];
      moving = true;
    }
    const int m = static_cast<int>(s.path_coefficients.cols());
    pd = s.path_coefficients.row(p * order + order - 1).transpose();
    dpd = Vector::Zero(m);
    ddpd = Vector::Zero(m);
    for (int j = order - 2; j >= 0; --j) {
      ddpd = ddpd * h + 2 * dpd;
      dpd = dpd * h + pd;
      pd = pd * h + s.path_coefficients.row(p * order + j).transpose();
    }
    if (!moving) {
      dpd.setZero();
      ddpd.setZero();
    }
  }

  Output compute(double t, const Vector &q, const Vector &v, const Vector &z) {
    Output out;
    out.z = z;
    const TaskState ts = nominal.task_state(q, v);
    const Matrix &J = ts.J;
    Vector pd, dpd, ddpd;
    path(t, pd, dpd, ddpd);
    Vector e, dxd, ddxd;
    if (s.pose) {  // PoseTrajectory.__call__ and tasks.task_error("pose")
      const double arg = s.rotation_omega * t + s.rotation_phase;
      const double theta = s.rotation_amplitude * std::sin(arg);
      const double dtheta = s.rotation_amplitude * s.rotation_omega * std::cos(arg);
      const double ddtheta = -s.rotation_amplitude * s.rotation_omega * s.rotation_omega * std::sin(arg);
      const Eigen::Matrix3d Rd = pinocchio::exp3(Vector3d(theta * s.rotation_axis)) * s.rotation0;
      e.resize(6);
      dxd.resize(6);
      ddxd.resize(6);
      e << ts.x - pd, pinocchio::log3(Eigen::Matrix3d(ts.R * Rd.transpose()));
      dxd << dpd, dtheta * s.rotation_axis;
      ddxd << ddpd, ddtheta * s.rotation_axis;
    } else {
      e = ts.x - pd;
      dxd = dpd;
      ddxd = ddpd;
    }
    const Vector de = J * v - dxd;
    double lam2 = 0.0;
    const Matrix inv = pinv_factor(J, lam2);
    const Matrix J_pinv = J.transpose() * inv;
    out.damping = lam2;
    if (s.law == "pd") {  // TaskSpacePD.compute
      Vector tau = J.transpose() * (-s.pd_Kp * e - s.pd_Kd * de) + nominal.gravity(q);
      tau -= s.null_damping * (v - J_pinv * (J * v));
      out.tau = tau;
      return out;
    }
    Vector y(2 * e.size());
    y << e, de;
    Vector u0 = Vector::Zero(e.size());
    if (s.robust == "nn") {
      const Vector w = s.BtP * y;
      Vector in(s.basis_joint ? 2 * q.size() : y.size());
      if (s.basis_joint) in << q, v;
      else in = y;
      const Vector phi = basis(in);
      const double rho = z.head(L).dot(phi);
      const double eps = std::max(z[L], 0.0);
      const double wn = w.norm(), denom = rho * wn + eps;
      if (denom > 0.0) u0 = -(s.law_corrected ? rho * rho : rho) * w / denom;
      out.rho_hat = rho;
      out.eps = z[L];
      out.z_norm = z.head(L).norm();
      // NNCompensator.advance: exact solution over the period with (w, phi) held
      const Vector drive = wn * phi;
      if (s.sigma > 0.0) {
        const double decay = std::exp(-s.F * s.sigma * s.period);
        out.z.head(L) = z.head(L) * decay + (drive / s.sigma) * (1.0 - decay);
      } else {
        out.z.head(L) = z.head(L) + s.F * s.period * drive;
      }
      out.z[L] = s.eps_min + (z[L] - s.eps_min) * std::exp(-s.gamma * s.period);
    } else if (s.robust == "sliding") {
      const Vector w = s.BtP * y;
      u0 = -s.sliding_gain * w / std::max(w.norm(), s.sliding_boundary);
    }
    const Vector task_acc = ddxd - ts.jdot_v - s.Kv * de - s.Kp * e + u0;
    Vector a = J_pinv * task_acc;
    if (s.k != 0.0) {
      const Vector grad = s.criteria.empty() ? Vector(Vector::Zero(q.size())) : criteria.gradient(nominal, q, ts);
      const Vector zz = grad - v;
      a += s.k * (zz - J_pinv * (J * zz));
    }
    Vector friction(q.size());
    for (int i = 0; i < q.size(); ++i) {
      const double sg = s.coulomb_smoothing <= 0 ? sign(v[i]) : std::clamp(v[i] / s.coulomb_smoothing, -1.0, 1.0);
      friction[i] = s.nominal_viscous[i] * v[i] + s.nominal_coulomb[i] * sg;
    }
    out.tau = nominal.inverse_dynamics(q, v, a) + friction;
    return out;
  }
};

// Result.from_trace's per-sample quantities of the true robot at q: the chain points, the
// manipulability sqrt(det(J J^T)) of the task Jacobian and the weighted criterion h.
void record_kinematics(LoadedModel &m, const LoopSpec &s, const Criteria &criteria, const Vector &q, long k,
                       LoopTrace &tr) {
  auto &model = m.model;
  auto &data = m.data;
  pin::computeJointJacobians(model, data, q);  // one kinematics pass: placements and Jacobians
  pin::updateFramePlacement(model, data, m.frame);
  const int joints = model.njoints - 1;
  for (int j = 0; j < joints; ++j) tr.chain.block<1, 3>(k, 3 * j) = data.oMi[j + 1].translation().transpose();
  tr.chain.block<1, 3>(k, 3 * joints) = data.oMf[m.frame].translation().transpose();
  pin::Matrix6x J6 = pin::Matrix6x::Zero(6, model.nv);
  pin::getFrameJacobian(model, data, m.frame, pinocchio::LOCAL_WORLD_ALIGNED, J6);
  const Matrix J = J6.topRows(s.m);
  tr.manipulability[k] = std::sqrt(std::max(det_small(J * J.transpose()), 0.0));
  if (!s.criteria.empty()) {
    const Matrix points = Eigen::Map<const Rows>(tr.chain.row(k).data(), joints + 1, 3);
    tr.h[k] = criteria.value(q, J, points);
  }
}

// simulation.step_rate: the fastest joint's speed, or the ring frequency of a stop a joint is at or
// would reach within the period, whichever is higher.
double step_rate(const LoopSpec &s, const Vector &q, const Vector &v) {
  double rate = v.cwiseAbs().maxCoeff();
  if (!s.stops || s.stop_ring.size() != q.size()) return rate;
  for (Eigen::Index i = 0; i < q.size(); ++i) {
    const double beyond = std::max(q[i] - s.stop_upper[i], s.stop_lower[i] - q[i]);
    if (beyond + std::abs(v[i]) * s.period > 0.0) rate = std::max(rate, s.stop_ring[i]);
  }
  return rate;
}

// simulation.period_substeps: the plant steps of one control period, cut for its step_rate.
int period_substeps(const LoopSpec &s, double speed) {
  const double needed = std::ceil(s.period * speed / s.max_step_rotation);
  return needed <= s.substeps ? s.substeps : static_cast<int>(std::min<double>(needed, s.max_period_substeps));
}

}  // namespace

LoopTrace run_loop(LoadedModel &model, LoadedModel *nominal_model, const LoopSpec &s, bool (*interrupted)(),
                   const ExternalLaw *external) {
  const int n = model.model.nv;
  const long steps = s.steps;
  LoopTrace tr;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  tr.q = Rows::Constant(steps, n, nan);
  tr.dq = tr.q;
  tr.tau = tr.q;
  tr.tau_cmd = tr.q;
  tr.z = Rows::Constant(steps, s.z0.size(), nan);
  tr.rho_hat = Vector::Constant(steps, nan);
  tr.eps = tr.rho_hat;
  tr.z_norm = tr.rho_hat;
  tr.damping = tr.rho_hat;
  tr.chain = Rows::Constant(steps, 3 * (model.model.njoints), nan);
  tr.manipulability = tr.rho_hat;
  tr.h = tr.rho_hat;
  std::unique_ptr<Nominal> nominal;
  if (s.nominal_kind == "pinocchio") nominal = std::make_unique<PinocchioNominal>(*nominal_model, s.m);
  else nominal = std::make_unique<ClosedFormNominal>(s.nominal);
  Controller controller(s, *nominal);
  Plant plant{model, s};
  std::unique_ptr<StickSlipIntegrator> stick_slip;
  if (plant.any_sticky() && !s.mj_step) stick_slip = std::make_unique<StickSlipIntegrator>(plant, s.v0);
  const bool noisy = s.noise_q.rows() > 0;
  Vector q = s.q0, v = s.v0, z = s.z0, tau = Vector::Zero(n);
  std::deque<Vector> commands;
  tr.done = steps;
  for (long k = 0; k < steps; ++k) {
    if (interrupted && k % 256 == 0 && k > 0 && interrupted()) {
      tr.status = "interrupted";
      tr.done = k;
      break;
    }
    const double t = static_cast<double>(k) * s.period;
    Vector qm = q, vm = v;  // Sensor.measure
    if (noisy) {
      for (int i = 0; i < n; ++i) {
        qm[i] = q[i] + s.position_noise[i] * s.noise_q(k, i);
        vm[i] = v[i] + s.velocity_noise[i] * s.noise_v(k, i);
        const double r = s.resolution[i];
        if (r > 0) qm[i] = std::nearbyint(qm[i] / r) * r;
      }
    }
    Output out;
    if (external) {
      out.z = z;
      if (!(*external)(t, qm, vm, z, out.tau, out.z)) {
        tr.status = "failed";
        tr.done = k;
        break;
      }
    } else {
      out = controller.compute(t, qm, vm, z);
    }
    commands.push_back(out.tau);
    if (static_cast<int>(commands.size()) > s.delay + 1) commands.pop_front();
    const Vector tau_cmd = commands.front();
    tau = tau_cmd;
    if (s.torque_limit.size()) tau = tau_cmd.cwiseMax(-s.torque_limit).cwiseMin(s.torque_limit);
    tr.q.row(k) = q;
    tr.dq.row(k) = v;
    tr.tau.row(k) = tau;
    tr.tau_cmd.row(k) = tau_cmd;
    if (z.size()) tr.z.row(k) = z;
    tr.rho_hat[k] = out.rho_hat;
    tr.eps[k] = out.eps;
    tr.z_norm[k] = out.z_norm;
    tr.damping[k] = out.damping;
    if (q.allFinite()) record_kinematics(model, s, controller.criteria, q, k, tr);
    if (!out.tau.allFinite() || !q.allFinite() || !v.allFinite()) {
      tr.status = "diverged";
      tr.divergence_index = k;
      tr.done = k + 1;
      break;
    }
    Eigen::Index worst;
    if (v.cwiseAbs().maxCoeff(&worst) > s.max_speed) {
      tr.status = "diverged";
      tr.divergence_index = k;
      tr.divergence_joint = static_cast<int>(worst);
      tr.done = k + 1;
      break;
    }
    z = out.z;
    plant.begin_period(t);  // the loads held over this period
    if (s.mj_step) {  // MujocoPlant.advance: MuJoCo's steps with tau held, -tau_d at each mid-step
      const double h = s.period / s.substeps;
      using Step = void (*)(const void *, void *);
      const auto step = reinterpret_cast<Step>(s.mj_step);
      auto *ctrl = reinterpret_cast<double *>(s.mj_ctrl);
      auto *applied = reinterpret_cast<double *>(s.mj_qfrc_applied);
      const auto *qpos = reinterpret_cast<const double *>(s.mj_qpos);
      const auto *qvel = reinterpret_cast<const double *>(s.mj_qvel);
      for (int i = 0; i < n; ++i) ctrl[i] = tau[i];
      for (int j = 0; j < s.substeps; ++j) {
        const double mid = t + (j + 0.5) * h;
        for (int i = 0; i < n; ++i) applied[s.mj_dof_index[i]] = -plant.disturbance(i, mid) + plant.load(i);
        step(reinterpret_cast<const void *>(s.mj_model), reinterpret_cast<void *>(s.mj_data));
      }
      for (int i = 0; i < n; ++i) {
        q[i] = qpos[s.mj_qpos_index[i]];
        v[i] = qvel[s.mj_dof_index[i]];
      }
      continue;
    }
    const int n_steps = period_substeps(s, step_rate(s, q, v));
    tr.refined_periods += n_steps != s.substeps;
    const double h = s.period / n_steps;
    if (stick_slip) {  // simulation.simulate with the plant's stick-slip integrator
      for (int i = 0; i < n_steps; ++i) stick_slip->advance(t + i * h, q, v, tau, h, i == 0);
      continue;
    }
    for (int i = 0; i < n_steps; ++i) {  // simulation._rk4_step with the torque held
      const double ti = t + i * h;
      const Vector k1q = v, k1v = plant.acceleration(ti, q, v, tau);
      const Vector k2q = v + 0.5 * h * k1v, k2v = plant.acceleration(ti + 0.5 * h, q + 0.5 * h * k1q, k2q, tau);
      const Vector k3q = v + 0.5 * h * k2v, k3v = plant.acceleration(ti + 0.5 * h, q + 0.5 * h * k2q, k3q, tau);
      const Vector k4q = v + h * k3v, k4v = plant.acceleration(ti + h, q + h * k3q, k4q, tau);
      q = q + (h / 6.0) * (k1q + 2.0 * k2q + 2.0 * k3q + k4q);
      v = v + (h / 6.0) * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
    }
  }
  if (stick_slip) {
    tr.friction_events = stick_slip->events_count();
    tr.unresolved_events = stick_slip->unresolved();
  }
  return tr;
}

namespace {
std::atomic<bool> batch_stop{false};
bool batch_stopped() { return batch_stop.load(); }
}  // namespace

std::vector<LoopTrace> run_batch(const std::vector<BatchItem> &items, int threads, bool (*interrupted)()) {
  std::vector<LoopTrace> traces(items.size());
  std::atomic<size_t> next{0};
  std::atomic<int> running{0};
  batch_stop = false;
  const int count = std::max(1, std::min<int>(threads, static_cast<int>(items.size())));
  std::vector<std::thread> pool;
  running = count;
  for (int w = 0; w < count; ++w)
    pool.emplace_back([&]() {
      for (size_t i = next++; i < items.size(); i = next++)
        traces[i] = run_loop(*items[i].plant, items[i].nominal, *items[i].spec, &batch_stopped);
      --running;
    });
  while (running.load() > 0) {  // the calling thread watches for Ctrl-C and SIGTERM
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    if (interrupted && !batch_stop.load() && interrupted()) batch_stop = true;
  }
  for (auto &t : pool) t.join();
  batch_stop = false;
  return traces;
}

}  // namespace nnrobust
