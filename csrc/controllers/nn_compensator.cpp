// NNCompensator (nnrobust/controllers/nn_compensator.py): u_0 of eq. (15) with rho-hat = Z^T phi(s),
// Z' = F (|w| phi(s) - sigma Z), eps' = -gamma (eps - eps_min), advanced exactly over the period
// with (w, phi) held; z = [Z, eps].
#include <algorithm>
#include <cmath>

#include "robust_term.hpp"

namespace nnrobust {
namespace {

struct NNCompensator : RobustTerm {
  Matrix BtP, centers;  // centers: dim(s) x K
  Vector inv2w2;        // dim(s)
  bool bias, joint_input, corrected;
  double F, gamma, eps_min, sigma;
  int L;

  explicit NNCompensator(const Fields &f)
      : BtP(f.matrix("BtP")), centers(f.matrix("centers")), inv2w2(f.vector("inv2w2")),
        bias(f.scalar("bias") != 0.0), joint_input(f.scalar("joint_input") != 0.0),
        corrected(f.scalar("corrected") != 0.0), F(f.scalar("F")), gamma(f.scalar("gamma")),
        eps_min(f.scalar("eps_min")), sigma(f.scalar("sigma")),
        L(static_cast<int>(bias) + static_cast<int>(centers.size())) {}

  // AdditiveRBFBasis.__call__: [1 (with bias), exp(-(s_j - c_jk)^2 inv2w2_j) for j, k]
  Vector basis(const Vector &in) const {
    Vector phi(L);
    int i = 0;
    if (bias) phi[i++] = 1.0;
    for (int j = 0; j < centers.rows(); ++j)
      for (int c = 0; c < centers.cols(); ++c) {
        const double d = in[j] - centers(j, c);
        phi[i++] = std::exp(-(d * d) * inv2w2[j]);
      }
    return phi;
  }

  // NNCompensator.output: u0 (corrected or printed form), then advance
  Vector output(const Vector &q, const Vector &v, const Vector &y, const Vector &z, double period, Vector &z_next,
                Vector &signals) const override {
    const Vector w = BtP * y;
    Vector in(joint_input ? 2 * q.size() : y.size());
    if (joint_input) in << q, v;
    else in = y;
    const Vector phi = basis(in);
    const double rho = z.head(L).dot(phi);
    const double eps = std::max(z[L], 0.0);
    const double wn = w.norm(), denom = rho * wn + eps;
    Vector u0 = Vector::Zero(w.size());
    if (denom > 0.0) u0 = -(corrected ? rho * rho : rho) * w / denom;
    signals.resize(3);
    signals << rho, z[L], z.head(L).norm();
    z_next = z;
    if (period <= 0.0) return u0;
    const Vector drive = wn * phi;
    if (sigma > 0.0) {
      const double decay = std::exp(-F * sigma * period);
      z_next.head(L) = z.head(L) * decay + (drive / sigma) * (1.0 - decay);
    } else {
      z_next.head(L) = z.head(L) + F * period * drive;
    }
    z_next[L] = eps_min + (z[L] - eps_min) * std::exp(-gamma * period);
    return u0;
  }
};

}  // namespace

NNROBUST_ROBUST_TERM("nn_compensator", NNCompensator);

}  // namespace nnrobust
