// SlotineLi (nnrobust/controllers/laws/slotine_li.py): task-space Slotine–Li adaptive control,
// Y(q, q', q'_r, q''_r) theta-hat - K_D s (K_D unset: K_D_step / T M-hat(q)), theta-hat advanced by
// explicit Euler over the period and projected (pseudo-inertias floored; the closed form's box).
#include <Eigen/Eigenvalues>
#include <memory>

#include "../../model/nominal.hpp"
#include "../../model/regressor.hpp"
#include "../../pin_calls.hpp"
#include "../../spectral.hpp"
#include "law.hpp"

namespace nnrobust {
namespace {

struct SlotineLi : Law {
  LawContext c;
  Vector Lambda, K_D, theta0, armature, pseudo_floor, lower, upper;
  double K_D_mass, gamma, leakage, null_damping, criterion_gain;
  bool exact, project;
  PinocchioNominal *pin_model = nullptr;  // else the closed form, one unit model per column of Y
  std::vector<ThreeLinkSpec> unit_specs;
  // the regressor's workspaces, sized here: a step allocates none of them (an exported law keeps
  // nothing it allocated in a step)
  Matrix Y_;
  ChristoffelWork christoffel_;
  // M-hat(q) s of the unset K_D by one RNEA of the nominal model without gravity (Pinocchio)
  pinocchio::Model weightless_;
  std::unique_ptr<pinocchio::Data> weightless_data_;
  Vector zero_;
  // the body whose pseudo-inertia had the least eigenvalue last step: solved first, the others
  // only tested against it (the least eigenvalue moves little from one step to the next)
  mutable int least_body_ = 0;

  SlotineLi(const LawParams &p, LawContext &context)
      : c(context), Lambda(p.vector("Lambda")), K_D(p.vector("K_D")), theta0(p.vector("theta0")),
        armature(p.vector("armature")), pseudo_floor(p.vector("pseudo_floor")), lower(p.vector("lower")),
        upper(p.vector("upper")), K_D_mass(p.scalar("K_D_mass")), gamma(p.scalar("gamma")),
        leakage(p.scalar("leakage")), null_damping(p.scalar("null_damping")),
        criterion_gain(p.scalar("criterion_gain")), exact(p.scalar("exact") != 0.0),
        project(p.scalar("project") != 0.0) {
    pin_model = dynamic_cast<PinocchioNominal *>(&c.nominal);
    if (!pin_model) {
      const ThreeLinkSpec &s = dynamic_cast<ClosedFormNominal &>(c.nominal).spec;
      for (int i = 0; i < 9; ++i) {  // theta = (beta, p, gamma)
        ThreeLinkSpec unit = s;
        unit.beta.setZero();
        unit.p.setZero();
        unit.gamma.setZero();
        (i < 3 ? unit.beta : i < 6 ? unit.p : unit.gamma)[i % 3] = 1.0;
        unit_specs.push_back(unit);
      }
    }
    const int n = pin_model ? pin_model->m.model.nv : 3;
    const int columns = pin_model ? 10 * (pin_model->m.model.njoints - 1) : 9;
    Y_.setZero(n, columns);
    christoffel_ = ChristoffelWork(n, columns);
    zero_.setZero(n);
    if (pin_model) {
      weightless_ = pin_model->m.model;
      weightless_.gravity.setZero();
      weightless_data_ = std::make_unique<pinocchio::Data>(weightless_);
    }
  }

  // pinocchio.computeJointTorqueRegressor(q, v, a) into Y (csrc/model/regressor.hpp)
  void joint_torque_regressor(const Vector &q, const Vector &v, const Vector &a, Matrix &Y) const {
    nnrobust::joint_torque_regressor(pin_model->m.model, pin_model->m.data, q, v, a, Y);
  }

  // Y with Y theta = M(q) a_r + C(q, v) v_r + G(q) (C(q, v_r) v_r when not exact), SlotineLi.regressor;
  // the law's own buffer, good until the next call. The exact form by polarisation of the bias:
  // on Pinocchio models in two passes (christoffel_regressor), on the closed form per column.
  const Matrix &regressor(const Vector &q, const Vector &v, const Vector &v_r, const Vector &a_r) {
    if (pin_model) {
      if (exact)
        christoffel_regressor(pin_model->m.model, pin_model->m.data, q, v, v_r, a_r, Y_, christoffel_);
      else
        joint_torque_regressor(q, v_r, a_r, Y_);
      return Y_;
    }
    const ThreeLinkTrig trig{Vector3d(q)};  // one pose, nine unit models
    const Vector3d plus = v + v_r, minus = v - v_r;
    for (int i = 0; i < 9; ++i) {
      const ThreeLink unit{unit_specs[i]};
      const Vector3d g = unit.bias(trig, Vector3d::Zero());
      const Vector3d coriolis = exact ? Vector3d(0.25 * (unit.bias(trig, plus) - unit.bias(trig, minus)))
                                      : Vector3d(unit.bias(trig, v_r) - g);
      Y_.col(i) = unit.mass(trig) * a_r + coriolis + g;
    }
    return Y_;
  }

  static Eigen::Matrix4d pseudo_inertia(const Vector &pi) {
    Eigen::Matrix3d I;
    I << pi[4], pi[5], pi[7], pi[5], pi[6], pi[8], pi[7], pi[8], pi[9];
    Eigen::Matrix4d P;
    P.topLeftCorner<3, 3>() = 0.5 * I.trace() * Eigen::Matrix3d::Identity() - I;
    P.topRightCorner<3, 1>() = pi.segment<3>(1);
    P.bottomLeftCorner<1, 3>() = pi.segment<3>(1).transpose();
    P(3, 3) = pi[0];
    return P;
  }

  double min_inertia_eigenvalue(const Vector &q, const Vector &theta) const {
    if (!pin_model) {
      const ThreeLinkTrig trig{Vector3d(q)};
      Eigen::Matrix3d M = Eigen::Matrix3d::Zero();
      for (int i = 0; i < 9; ++i) M += theta[i] * ThreeLink{unit_specs[i]}.mass(trig);
      return Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(M, Eigen::EigenvaluesOnly).eigenvalues()[0];
    }
    const auto least = [&](int body) {
      const Eigen::Matrix4d P = pseudo_inertia(theta.segment(10 * body, 10));
      return Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d>(P, Eigen::EigenvaluesOnly).eigenvalues()[0];
    };
    const int first = least_body_;
    double lowest = least(first);
    for (int body = 0; body < theta.size() / 10; ++body) {
      // this body's least eigenvalue above the least so far: it is not the least (a tie within
      // rounding decides nothing)
      if (body == first || eigenvalues_above(pseudo_inertia(theta.segment(10 * body, 10)), lowest)) continue;
      const double value = least(body);
      if (value < lowest) {
        lowest = value;
        least_body_ = body;
      }
    }
    return lowest;
  }

  // SlotineLi.projected
  Vector projected(const Vector &theta) const {
    if (!pin_model) return theta.cwiseMax(lower).cwiseMin(upper);  // the closed form's box
    Vector out = theta;
    for (int k = 0, i = 0; i < theta.size(); ++k, i += 10) {
      const Eigen::Matrix4d P0 = pseudo_inertia(theta.segment(i, 10));
      // every eigenvalue above the floor: nothing to project, and no decomposition (within
      // rounding of the floor, the decomposition below decides)
      if (eigenvalues_above(P0, pseudo_floor[k])) continue;
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> eig(P0);
      if (eig.eigenvalues()[0] >= pseudo_floor[k]) continue;
      const Eigen::Vector4d w = eig.eigenvalues().cwiseMax(pseudo_floor[k]);
      const Eigen::Matrix4d P = eig.eigenvectors() * w.asDiagonal() * eig.eigenvectors().transpose();
      const Eigen::Matrix3d I = P.topLeftCorner<3, 3>().trace() * Eigen::Matrix3d::Identity() - P.topLeftCorner<3, 3>();
      out.segment(i, 10) << P(3, 3), P(0, 3), P(1, 3), P(2, 3), I(0, 0), I(0, 1), I(1, 1), I(0, 2), I(1, 2), I(2, 2);
    }
    return out;
  }

  // M-hat(q) s (SlotineLi.damping's RNEA(q, 0, s) - G(q))
  Vector mass_times(const Vector &q, const Vector &s) {
    if (!pin_model) return dynamic_cast<ClosedFormNominal &>(c.nominal).model.mass(Vector3d(q)) * Vector3d(s);
    return pin::rnea(weightless_, *weightless_data_, q, zero_, s);
  }

  // SlotineLi.compute
  Output compute(double t, const Vector &q, const Vector &v, const Vector &z) override {
    const TaskReference r = c.shared.reference(t, q, v);
    const Matrix &J = r.ts.J;
    double lam2 = 0.0;
    const Matrix J_pinv = J.transpose() * c.shared.pinv_factor(J, lam2);
    Vector null = -null_damping * v;
    if (criterion_gain != 0.0 && !c.spec.criteria.empty())
      null += criterion_gain * c.shared.criteria.gradient(c.nominal, q, r.ts);
    const Vector v_r = J_pinv * (r.dxd - Lambda.cwiseProduct(r.e)) + (null - J_pinv * (J * null));
    const Vector a_r = J_pinv * (r.ddxd - Lambda.cwiseProduct(r.de) - r.ts.jdot_v);
    const Vector s = v - v_r;
    const Matrix &Y = regressor(q, v, v_r, a_r);
    Output out;
    Vector damping = K_D.cwiseProduct(s);  // SlotineLi.damping: K_D s, or K_D_step / T M-hat(q) s
    if (K_D_mass != 0.0) damping += K_D_mass * mass_times(q, s);
    out.tau = Y * z + armature.cwiseProduct(a_r) - damping + c.shared.nominal_friction(v);
    out.z = z + c.spec.period * (-gamma * (Y.transpose() * s) - leakage * (z - theta0));
    if (project) out.z = projected(out.z);
    out.signals.resize(3);
    out.signals << (z - theta0).norm(), s.norm(), min_inertia_eigenvalue(q, z);
    return out;
  }
};

}  // namespace

NNROBUST_LAW("slotine_li", SlotineLi);

}  // namespace nnrobust
