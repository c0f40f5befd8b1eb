// RBFNN (nnrobust/controllers/laws/rbf_nn.py): eq. (9) with u_0 = -W^T phi(s) - k_z (|W|_F + W_B) w,
// W' = F (phi w^T - kappa |w| W) solved exactly over the period with (w, phi) held; z is W by columns.
#include "law.hpp"

namespace nnrobust {
namespace {

struct RBFNN : Law {
  LawContext c;
  Matrix Kp, Kv, BtP, centers;
  Vector inv2w2;
  double k, F, kappa, k_z, W_B;
  bool joint_input;

  RBFNN(const LawParams &p, LawContext &context)
      : c(context), Kp(p.matrix("Kp")), Kv(p.matrix("Kv")), BtP(p.matrix("BtP")), centers(p.matrix("centers")),
        inv2w2(p.vector("inv2w2")), k(p.scalar("k")), F(p.scalar("F")), kappa(p.scalar("kappa")),
        k_z(p.scalar("k_z")), W_B(p.scalar("W_B")), joint_input(p.scalar("joint_input") != 0.0) {}

  // AdditiveRBFBasis.__call__ with its constant unit: [1, exp(-(s_j - c_jk)^2 inv2w2_j) for j, k]
  Vector basis(const Vector &in) const {
    Vector phi(1 + centers.size());
    phi[0] = 1.0;
    int i = 1;
    for (int j = 0; j < centers.rows(); ++j)
      for (int col = 0; col < centers.cols(); ++col) {
        const double d = in[j] - centers(j, col);
        phi[i++] = std::exp(-(d * d) * inv2w2[j]);
      }
    return phi;
  }

  // TaskSpaceController.compute with RBFCompensator.output
  Output compute(double t, const Vector &q, const Vector &v, const Vector &z) override {
    const TaskReference r = c.shared.reference(t, q, v);
    const int m = static_cast<int>(r.e.size());
    Vector y(2 * m);
    y << r.e, r.de;
    const Vector w = BtP * y;
    Vector in(joint_input ? 2 * q.size() : y.size());
    if (joint_input) in << q, v;
    else in = y;
    const Vector phi = basis(in);
    const int L = static_cast<int>(phi.size());
    const Eigen::Map<const Matrix> W(z.data(), L, m);
    const Vector eta_hat = W.transpose() * phi;
    const double size = W.norm(), wn = w.norm();
    const Vector u0 = -eta_hat - k_z * (size + W_B) * w;
    Output out;
    out.z.resize(z.size());
    Eigen::Map<Matrix> W_next(out.z.data(), L, m);
    const Matrix drive = phi * w.transpose();
    const double rate = F * kappa * wn;
    if (rate > 0.0) {
      const double decay = std::exp(-rate * c.spec.period);
      W_next = W * decay + (drive / (kappa * wn)) * (1.0 - decay);
    } else {
      W_next = W + F * c.spec.period * drive;
    }
    double lam2 = 0.0;
    const Matrix J_pinv = r.ts.J.transpose() * c.shared.pinv_factor(r.ts.J, lam2);
    out.tau = c.shared.eq9_torque(q, v, r, J_pinv, u0, Kp, Kv, k);
    out.signals.resize(3);
    out.signals << eta_hat.norm(), size, lam2;
    return out;
  }
};

}  // namespace

NNROBUST_LAW("rbf_nn", RBFNN);

}  // namespace nnrobust
