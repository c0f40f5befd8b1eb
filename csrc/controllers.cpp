#include "controllers.hpp"

#include <algorithm>
#include <stdexcept>

#include <Eigen/Eigenvalues>
#include <pinocchio/spatial/explog.hpp>

#include "controllers/laws/law.hpp"
#include "spectral.hpp"

namespace nnrobust {

Controller::Controller(const LoopSpec &spec, Nominal &model)
    : s(spec), nominal(model), criteria(spec),
      friction(Fields{"LoopSpec.nominal_friction: the controller's friction", spec.nominal_friction}) {
  const auto path_factory = PathRegistry::find(spec.path);
  if (!path_factory) throw std::invalid_argument("LoopSpec.path: unknown path " + spec.path);
  path = path_factory(Fields{"LoopSpec.path_params: the path " + spec.path, spec.path_params});
  if (spec.pose) orientation.emplace(Fields{"LoopSpec.pose_params: the pose trajectory", spec.pose_params});
  const auto factory = LawRegistry::find(spec.law);
  if (!factory) throw std::invalid_argument("LoopSpec.law: unknown law " + spec.law);
  LawContext context{spec, model, *this};
  law = factory(LawParams{"LoopSpec.law_params: the law " + spec.law, spec.law_params}, context);
}

Controller::~Controller() = default;

// DampedPseudoInverse.factor
Matrix Controller::pinv_factor(const Matrix &J, double &lam2) const {
  const Matrix JJt = J * J.transpose();
  const double thr_sq = s.pinv_threshold * s.pinv_threshold;
  if (eigenvalues_above(JJt, thr_sq)) {  // sigma_min above the threshold: no damping, no eigen-solve
    lam2 = 0.0;
  } else {
    const double sigma_min_sq =
        std::max(Eigen::SelfAdjointEigenSolver<Matrix>(JJt, Eigen::EigenvaluesOnly).eigenvalues()[0], 0.0);
    lam2 = sigma_min_sq >= thr_sq ? 0.0 : s.pinv_max_damping * s.pinv_max_damping * (1.0 - sigma_min_sq / thr_sq);
  }
  return (JJt + lam2 * Matrix::Identity(J.rows(), J.rows())).inverse();
}

const TaskReference &Controller::reference_kept(double t, const Vector &q, const Vector &v) const {
  TaskReference r = reference(t, q, v);
  if (kept_)
    *kept_ = std::move(r);  // the slot of the last one: its arrays are r's, moved, not copied
  else
    kept_ = std::make_unique<TaskReference>(std::move(r));
  kept_valid_ = true;
  kept_t_ = t;
  kept_q_ = q;
  kept_v_ = v;
  return *kept_;
}

TaskReference Controller::reference(double t, const Vector &q, const Vector &v) const {
  if (kept_valid_) {  // observed at this (t, q, v) just before: the same numbers (the nominal
                      // model's data too: nothing ran on it since); taken once
    kept_valid_ = false;
    if (t == kept_t_ && q == kept_q_ && v == kept_v_) return std::move(*kept_);
  }
  TaskReference r{nominal.task_state(q, v), {}, {}, {}, {}};
  const TaskState &ts = r.ts;
  Vector pd, dpd, ddpd;
  path->at(t, pd, dpd, ddpd);
  if (orientation) {  // PoseTrajectory.__call__ and tasks.task_error("pose")
    Eigen::Matrix3d Rd;
    Eigen::Vector3d w, dw;
    orientation->at(t, Rd, w, dw);
    r.e.resize(6);
    r.dxd.resize(6);
    r.ddxd.resize(6);
    r.e << ts.x - pd, pinocchio::log3(Eigen::Matrix3d(ts.R * Rd.transpose()));
    r.dxd << dpd, w;
    r.ddxd << ddpd, dw;
  } else {
    r.e = ts.x - pd;
    r.dxd = dpd;
    r.ddxd = ddpd;
  }
  r.de = ts.J * v - r.dxd;
  return r;
}

// the law's compute (LoopSpec.law)
Output Controller::compute(double t, const Vector &q, const Vector &v, const Vector &z) {
  return law->compute(t, q, v, z);
}

// TaskSpaceController.compute after u_0: M-hat a + N-hat + F-hat with
// a = J+ (x_d'' - J'q' - Kv e' - Kp e + u_0) + k (I - J+J)(grad h - q')
Vector Controller::eq9_torque(const Vector &q, const Vector &v, const TaskReference &r, const Matrix &J_pinv,
                              const Vector &u0, const Matrix &Kp, const Matrix &Kv, double k) {
  const Matrix &J = r.ts.J;
  const Vector task_acc = r.ddxd - r.ts.jdot_v - Kv * r.de - Kp * r.e + u0;
  Vector a = J_pinv * task_acc;
  if (k != 0.0) {
    const Vector grad = s.criteria.empty() ? Vector(Vector::Zero(q.size())) : criteria.gradient(nominal, q, r.ts);
    const Vector zz = grad - v;
    a += k * (zz - J_pinv * (J * zz));
  }
  return nominal.inverse_dynamics(q, v, a) + nominal_friction(v);
}

// Friction.torque of the controller's F-hat
Vector Controller::nominal_friction(const Vector &v) const {
  Vector torque(v.size());
  for (int i = 0; i < v.size(); ++i) torque[i] = friction.torque(i, v[i]);
  return torque;
}

}  // namespace nnrobust
