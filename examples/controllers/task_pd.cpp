// TaskPD in C++: examples/custom_controller.py's law written against nnrobust's law header, as one
// file an experiment names like a Python class (docs/extending.md#a-law-in-c):
//
//     [controller]
//     kind = "custom"
//     class = "controllers/task_pd.cpp:TaskPD"
//     params = { Kp = 100.0, Kd = 20.0, damping = 5.0 }
//
// a = J+ (x_d'' - J'q' - Kd e' - Kp e) - damping (I - J+ J) q',  tau = M-hat a + N-hat + F-hat(q')
// with J+ the experiment's damped pseudo-inverse; its one signal is |tau|.
#include "nnrobust/law.hpp"

using nnrobust::LawContext;
using nnrobust::LawParams;
using nnrobust::Matrix;
using nnrobust::Output;
using nnrobust::TaskReference;
using nnrobust::Vector;

struct TaskPD : nnrobust::Law {
  LawContext context;
  double Kp, Kd, damping;  // no defaults: every number comes from the experiment's params

  TaskPD(const LawParams &p, LawContext &c)
      : context(c), Kp(p.scalar("Kp")), Kd(p.scalar("Kd")), damping(p.scalar("damping")) {}

  Output compute(double t, const Vector &q, const Vector &v, const Vector &z) override {
    const TaskReference r = context.shared.reference(t, q, v);  // x, J, J'q' and e, e', x_d', x_d''
    const Matrix &J = r.ts.J;
    double lam2 = 0.0;
    const Matrix J_pinv = J.transpose() * context.shared.pinv_factor(J, lam2);
    Vector a = J_pinv * (r.ddxd - r.ts.jdot_v - Kd * r.de - Kp * r.e);
    a -= damping * (v - J_pinv * (J * v));
    const Vector tau = context.nominal.inverse_dynamics(q, v, a) + context.shared.nominal_friction(v);
    Vector signals(1);
    signals << tau.norm();
    return {tau, z, signals};
  }
};

NNROBUST_USER_LAW(TaskPD, "effort", 0)
// what `nnrobust tune` searches (as the Python TaskPD's search_space)
NNROBUST_USER_LAW_SPACE(TaskPD, "Kp=10:1e5:1/s^2, Kd=1:1e3:1/s, damping=0.1:100:1/s")
