// The true robot's right-hand side: the twin of nnrobust/plant/plant.py (friction, sinusoidal
// disturbance, joint stops, forward dynamics), included by closed_loop.cpp only.
#pragma once

#include <algorithm>
#include <cmath>

#include <pinocchio/algorithm/aba.hpp>
#include <pinocchio/algorithm/crba.hpp>
#include <pinocchio/algorithm/rnea.hpp>

#include "closed_loop.hpp"

namespace nnrobust {

inline double sign(double x) { return (x > 0) - (x < 0); }

using Modes = Eigen::VectorXi;  // per joint: +1 / -1 slipping, 0 held (nnrobust.plant.stick_slip)

struct Plant {
  LoadedModel &m;
  const LoopSpec &s;

  // Friction.static > 0: the joint is integrated as stick-slip (Plant.sticky)
  bool sticky(int i) const { return s.static_friction.size() && s.static_friction[i] > 0; }
  bool any_sticky() const {
    for (int i = 0; i < s.static_friction.size(); ++i)
      if (sticky(i)) return true;
    return false;
  }

  double disturbance(int i, double t) const {  // SinusoidalDisturbance.__call__
    double d = 0.0;
    for (int c = 0; c < s.dist_omega.size(); ++c)
      d += s.dist_amplitude(i, c) * std::sin(s.dist_omega[c] * t + s.dist_phase(i, c));
    return d;
  }

  double stop_torque(int i, double q, double v) const {  // JointStops.torque
    if (!s.stops) return 0.0;
    const double pen = std::max(q - s.stop_upper[i], 0.0) + std::min(q - s.stop_lower[i], 0.0);
    if (pen == 0.0) return 0.0;
    const double sg = sign(pen);
    return -sg * std::max(s.stop_stiffness[i] * std::abs(pen) * (1.0 + s.stop_alpha * sg * v), 0.0);
  }

  // Plant.acceleration: the slipping law with sgn(0) = 0
  Vector acceleration(double t, const Vector &q, const Vector &v, const Vector &tau) {
    const int n = static_cast<int>(q.size());
    Vector net = tau;
    for (int i = 0; i < n; ++i) {
      net[i] -= s.viscous[i] * v[i] + s.coulomb[i] * sign(v[i]) + disturbance(i, t);
      net[i] += stop_torque(i, q[i], v[i]);
    }
    return pinocchio::aba(m.model, m.data, q, v, net);
  }

  // Plant.net_torque: tau + tau_stop - tau_d - F, the sticky joints' dry friction F_c mode_i
  Vector net_torque(double t, const Vector &q, const Vector &v, const Vector &tau, const Modes &mode) const {
    const int n = static_cast<int>(q.size());
    Vector net(n);
    for (int i = 0; i < n; ++i) {
      const double friction = sticky(i) ? s.viscous[i] * v[i] + s.coulomb[i] * mode[i]
                                        : s.viscous[i] * v[i] + s.coulomb[i] * sign(v[i]);
      net[i] = tau[i] - friction - disturbance(i, t);
      net[i] += stop_torque(i, q[i], v[i]);
    }
    return net;
  }

  // M(q) with both triangles (PinocchioModel.mass)
  Matrix mass(const Vector &q) {
    pinocchio::crba(m.model, m.data, q);
    Matrix M = m.data.M;
    M.triangularView<Eigen::StrictlyLower>() = M.transpose();
    return M;
  }

  // Plant.constrained_acceleration: q'' with the held joints' q''_i = 0, and `hold`, the
  // friction torque holding them (in joint order)
  Vector constrained_acceleration(double t, const Vector &q, const Vector &v, const Vector &tau, const Modes &mode,
                                  Vector &hold) {
    const int n = static_cast<int>(q.size());
    const Vector net = net_torque(t, q, v, tau, mode);
    int held = 0;
    for (int i = 0; i < n; ++i) held += sticky(i) && mode[i] == 0;
    if (held == 0) {
      hold.resize(0);
      return pinocchio::aba(m.model, m.data, q, v, net);
    }
    const Matrix M = mass(q);
    const Vector r = net - pinocchio::nonLinearEffects(m.model, m.data, q, v);
    std::vector<int> free_idx, held_idx;
    for (int i = 0; i < n; ++i) (sticky(i) && mode[i] == 0 ? held_idx : free_idx).push_back(i);
    Vector a = Vector::Zero(n);
    const int nf = static_cast<int>(free_idx.size());
    if (nf) {
      Matrix Mff(nf, nf);
      Vector rf(nf);
      for (int i = 0; i < nf; ++i) {
        rf[i] = r[free_idx[i]];
        for (int j = 0; j < nf; ++j) Mff(i, j) = M(free_idx[i], free_idx[j]);
      }
      const Vector af = Mff.partialPivLu().solve(rf);
      for (int i = 0; i < nf; ++i) a[free_idx[i]] = af[i];
    }
    hold.resize(held);
    for (int i = 0; i < held; ++i) hold[i] = r[held_idx[i]] - M.row(held_idx[i]).dot(a);
    return a;
  }
};

}  // namespace nnrobust
