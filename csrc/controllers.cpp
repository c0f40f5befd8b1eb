#include "controllers.hpp"

#include "laws/law.hpp"

#include <algorithm>
#include <stdexcept>

#include <Eigen/Eigenvalues>
#include <pinocchio/spatial/explog.hpp>

namespace nnrobust {

Controller::Controller(const LoopSpec &spec, Nominal &model) : s(spec), nominal(model), criteria(spec) {
  L = static_cast<int>(spec.basis_bias) + static_cast<int>(spec.basis_centers.size());
  if (spec.law != "pd" && spec.law != "task-space" && spec.law != "external") {
    const LawFactory factory = find_law(spec.law);
    if (!factory) throw std::invalid_argument("LoopSpec.law: unknown law " + spec.law);
    LawContext context{spec, model, *this};
    law = factory(LawParams{"LoopSpec.law_params: the law " + spec.law, spec.law_params}, context);
  }
  if (spec.robust != "none" && spec.robust != "nn" && spec.robust != "sliding")
    throw std::invalid_argument("LoopSpec.robust: unknown robust term " + spec.robust);
  if (spec.path_kind != "ellipse" && spec.path_kind != "piecewise")
    throw std::invalid_argument("LoopSpec.path_kind: unknown path " + spec.path_kind);
  law_pd = spec.law == "pd";
  piecewise = spec.path_kind == "piecewise";
  robust = spec.robust == "nn" ? Robust::nn : spec.robust == "sliding" ? Robust::sliding : Robust::none;
}

Controller::~Controller() = default;

// AdditiveRBFBasis.__call__
Vector Controller::basis(const Vector &in) const {
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

// DampedPseudoInverse.factor
Matrix Controller::pinv_factor(const Matrix &J, double &lam2) const {
  const Matrix JJt = J * J.transpose();
  const double sigma_min_sq =
      std::max(Eigen::SelfAdjointEigenSolver<Matrix>(JJt, Eigen::EigenvaluesOnly).eigenvalues()[0], 0.0);
  const double thr_sq = s.pinv_threshold * s.pinv_threshold;
  lam2 = sigma_min_sq >= thr_sq ? 0.0 : s.pinv_max_damping * s.pinv_max_damping * (1.0 - sigma_min_sq / thr_sq);
  return (JJt + lam2 * Matrix::Identity(J.rows(), J.rows())).inverse();
}

// EllipseTrajectory or PiecewisePolynomialPath.__call__
void Controller::path(double t, Vector &pd, Vector &dpd, Vector &ddpd) const {
  if (!piecewise) {
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

TaskReference Controller::reference(double t, const Vector &q, const Vector &v) const {
  TaskReference r{nominal.task_state(q, v), {}, {}, {}, {}};
  const TaskState &ts = r.ts;
  Vector pd, dpd, ddpd;
  path(t, pd, dpd, ddpd);
  if (s.pose) {  // PoseTrajectory.__call__ and tasks.task_error("pose")
    const double arg = s.rotation_omega * t + s.rotation_phase;
    const double theta = s.rotation_amplitude * std::sin(arg);
    const double dtheta = s.rotation_amplitude * s.rotation_omega * std::cos(arg);
    const double ddtheta = -s.rotation_amplitude * s.rotation_omega * s.rotation_omega * std::sin(arg);
    const Eigen::Matrix3d Rd = pinocchio::exp3(Vector3d(theta * s.rotation_axis)) * s.rotation0;
    r.e.resize(6);
    r.dxd.resize(6);
    r.ddxd.resize(6);
    r.e << ts.x - pd, pinocchio::log3(Eigen::Matrix3d(ts.R * Rd.transpose()));
    r.dxd << dpd, dtheta * s.rotation_axis;
    r.ddxd << ddpd, ddtheta * s.rotation_axis;
  } else {
    r.e = ts.x - pd;
    r.dxd = dpd;
    r.ddxd = ddpd;
  }
  r.de = ts.J * v - r.dxd;
  return r;
}

// TaskSpaceController.compute (eq. 9 with u_0 and the null-space term of eq. 3), or TaskSpacePD's;
// a registered law's own compute
Output Controller::compute(double t, const Vector &q, const Vector &v, const Vector &z) {
  if (law) return law->compute(t, q, v, z);
  Output out;
  out.z = z;
  const TaskReference r = reference(t, q, v);
  const TaskState &ts = r.ts;
  const Matrix &J = ts.J;
  const Vector &e = r.e, &de = r.de;
  double lam2 = 0.0;
  const Matrix inv = pinv_factor(J, lam2);
  const Matrix J_pinv = J.transpose() * inv;
  out.damping = lam2;
  if (law_pd) {  // TaskSpacePD.compute
    Vector tau = J.transpose() * (-s.pd_Kp * e - s.pd_Kd * de) + nominal.gravity(q);
    tau -= s.null_damping * (v - J_pinv * (J * v));
    out.tau = tau;
    return out;
  }
  Vector y(2 * e.size());
  y << e, de;
  Vector u0 = Vector::Zero(e.size());
  if (robust == Robust::nn) {
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
  } else if (robust == Robust::sliding) {
    const Vector w = s.BtP * y;
    u0 = -s.sliding_gain * w / std::max(w.norm(), s.sliding_boundary);
  }
  out.tau = eq9_torque(q, v, r, J_pinv, u0, s.Kp, s.Kv, s.k);
  return out;
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
  Vector friction(v.size());
  for (int i = 0; i < v.size(); ++i) {
    const double sg = s.coulomb_smoothing <= 0 ? sign(v[i]) : std::clamp(v[i] / s.coulomb_smoothing, -1.0, 1.0);
    friction[i] = s.nominal_viscous[i] * v[i] + s.nominal_coulomb[i] * sg;
  }
  return friction;
}

}  // namespace nnrobust
