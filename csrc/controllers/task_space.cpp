// The task-space laws of nnrobust/controllers/task_space.py: TaskSpaceController (eq. 9, with the
// robust term LoopSpec.robust built from LoopSpec.robust_params, or u_0 = 0) and TaskSpacePD.
#include <stdexcept>

#include "laws/law.hpp"
#include "robust_term.hpp"

namespace nnrobust {
namespace {

struct TaskSpace : Law {
  LawContext c;
  Matrix Kp, Kv;
  const Matrix Kp_own, Kv_own;  // the law's own gains (scale_gains multiplies these)
  double k;
  std::unique_ptr<RobustTerm> robust;  // none: u_0 = 0

  TaskSpace(const LawParams &p, LawContext &context)
      : c(context), Kp(p.matrix("Kp")), Kv(p.matrix("Kv")), Kp_own(Kp), Kv_own(Kv), k(p.scalar("k")) {
    const std::string &name = c.spec.robust;
    if (name.empty()) return;
    const auto factory = RobustTermRegistry::find(name);
    if (!factory) throw std::invalid_argument("LoopSpec.robust: unknown robust term " + name);
    robust = factory(Fields{"LoopSpec.robust_params: the robust term " + name, c.spec.robust_params});
  }

  // TaskSpaceController.compute: signals are the robust term's, then the pseudo-inverse's damping
  Output compute(double t, const Vector &q, const Vector &v, const Vector &z) override {
    const TaskReference r = c.shared.reference(t, q, v);
    Vector y(2 * r.e.size());
    y << r.e, r.de;
    Output out;
    Vector u0 = Vector::Zero(r.e.size()), signals;
    if (robust) u0 = robust->output(q, v, y, z, c.spec.period, out.z, signals);
    else out.z = z;
    double lam2 = 0.0;
    const Matrix J_pinv = r.ts.J.transpose() * c.shared.pinv_factor(r.ts.J, lam2);
    out.tau = c.shared.eq9_torque(q, v, r, J_pinv, u0, Kp, Kv, k);
    out.signals.resize(signals.size() + 1);
    out.signals << signals, lam2;
    return out;
  }

  bool scale_gains(double position, double velocity) override {
    Kp = position * Kp_own;
    Kv = velocity * Kv_own;
    return true;
  }
};

struct TaskSpacePD : Law {
  LawContext c;
  Matrix Kp, Kd;
  const Matrix Kp_own, Kd_own;  // the law's own gains (scale_gains multiplies these)
  double null_damping;

  TaskSpacePD(const LawParams &p, LawContext &context)
      : c(context),
        Kp(p.matrix("Kp")),
        Kd(p.matrix("Kd")),
        Kp_own(Kp),
        Kd_own(Kd),
        null_damping(p.scalar("null_damping")) {}

  bool scale_gains(double position, double velocity) override {
    Kp = position * Kp_own;
    Kd = velocity * Kd_own;
    return true;
  }

  // TaskSpacePD.compute: J^T (-Kp e - Kd e') + G-hat - D (I - J+J) q'
  Output compute(double t, const Vector &q, const Vector &v, const Vector &z) override {
    const TaskReference r = c.shared.reference(t, q, v);
    const Matrix &J = r.ts.J;
    double lam2 = 0.0;
    const Matrix J_pinv = J.transpose() * c.shared.pinv_factor(J, lam2);
    Output out;
    out.z = z;
    out.tau = J.transpose() * (-Kp * r.e - Kd * r.de) + c.nominal.gravity(q);
    out.tau -= null_damping * (v - J_pinv * (J * v));
    out.signals = Vector::Constant(1, lam2);
    return out;
  }
};

}  // namespace

NNROBUST_LAW("task_space", TaskSpace);
NNROBUST_LAW("task_space_pd", TaskSpacePD);

}  // namespace nnrobust
