// JointFourierTracking (nnrobust/controllers/laws/joint_fourier.py): joint-space computed torque
// along a finite-Fourier joint trajectory, tau = M-hat(q) (q''_d + K_v (q'_d - q') + K_p (q_d - q))
// + N-hat(q, q') + F-hat(q'), the reference summed harmonic by harmonic as the Python law sums it.
#include <cmath>

#include "law.hpp"

namespace nnrobust {
namespace {

struct JointFourier : Law {
  LawContext c;
  Vector q_mean;
  Matrix sine, cosine;
  double omega, Kp, Kv;

  JointFourier(const LawParams &p, LawContext &context)
      : c(context), q_mean(p.vector("q_mean")), sine(p.matrix("sine")), cosine(p.matrix("cosine")),
        omega(p.scalar("omega")), Kp(p.scalar("Kp")), Kv(p.scalar("Kv")) {}

  Output compute(double t, const Vector &q, const Vector &v, const Vector &z) override {
    (void)z;
    Vector q_d = q_mean;
    Vector dq_d = Vector::Zero(q.size()), ddq_d = Vector::Zero(q.size());
    for (int l = 0; l < sine.cols(); ++l) {
      const double rate = omega * (l + 1);
      const double s = std::sin(rate * t), co = std::cos(rate * t);
      for (int i = 0; i < q.size(); ++i) {
        const double a = sine(i, l), b = cosine(i, l);
        q_d[i] += (a * s - b * co) / rate;
        dq_d[i] += a * co + b * s;
        ddq_d[i] += rate * (b * co - a * s);
      }
    }
    const Vector acc = ddq_d + Kv * (dq_d - v) + Kp * (q_d - q);
    Output out;
    out.tau = c.nominal.inverse_dynamics(q, v, acc) + c.shared.nominal_friction(v);
    return out;
  }
};

}  // namespace

NNROBUST_LAW("joint_fourier", JointFourier);

}  // namespace nnrobust
