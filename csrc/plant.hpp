// The true robot's right-hand side: the twin of nnrobust/plant/plant.py (friction, sinusoidal
// disturbance, external loads, joint stops, forward dynamics), included by closed_loop.cpp only.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <Eigen/Cholesky>

#include "pin_calls.hpp"

#include "closed_loop.hpp"

namespace nnrobust {

using Modes = Eigen::VectorXi;  // per joint: +1 / -1 slipping, 0 held (nnrobust.plant.stick_slip)

struct Plant {
  LoadedModel &m;
  const LoopSpec &s;

  Plant(LoadedModel &model, const LoopSpec &spec) : m(model), s(spec) {}

  // Friction.static > 0: the joint is integrated as stick-slip (Plant.sticky)
  bool sticky(int i) const { return s.static_friction.size() && s.static_friction[i] > 0; }
  bool any_sticky() const {
    for (int i = 0; i < s.static_friction.size(); ++i)
      if (sticky(i)) return true;
    return false;
  }

  // SinusoidalDisturbance.__call__, kept for the last time asked (RK4 asks twice at t + h / 2,
  // and a step's end is the next step's start)
  double disturbance(int i, double t) {
    if (t != dist_t_ || dist_.size() != s.dist_amplitude.rows()) {
      dist_.resize(s.dist_amplitude.rows());
      for (int j = 0; j < dist_.size(); ++j) {
        double d = 0.0;
        for (int c = 0; c < s.dist_omega.size(); ++c)
          d += s.dist_amplitude(j, c) * std::sin(s.dist_omega[c] * t + s.dist_phase(j, c));
        dist_[j] = d;
      }
      dist_t_ = t;
    }
    return dist_[i];
  }

  // Plant.begin_period: the loads of [[plant.loads]] held over the control period that starts at t
  // (the joint torque and the tool wrench; the payload's inertia set on its joint)
  void begin_period(double t) {
    const int n = static_cast<int>(s.q0.size());
    load_.setZero(n);
    for (int p = 0; p < s.pulse_start.size(); ++p)
      if (s.pulse_start[p] <= t && t < s.pulse_end[p]) load_ += s.pulse_torque.col(p);
    wrench_.setZero(6);
    has_wrench_ = false;
    for (int w = 0; w < s.wrench_start.size(); ++w)
      if (s.wrench_start[w] <= t && t < s.wrench_end[w]) {
        wrench_ += s.wrench.col(w);
        has_wrench_ = true;
      }
    const int changes = static_cast<int>(s.payload_start.size());
    if (changes) {
      int carried = 0;  // changes so far (sorted by start)
      for (int c = 0; c < changes; ++c) carried += s.payload_start[c] <= t;
      const int index = carried ? carried - 1 : changes;  // the last column: before any change
      if (index != payload_index_) {
        m.model.inertias[s.payload_joint] = pinocchio::Inertia::FromDynamicParameters(s.payload_inertia.col(index));
        payload_index_ = index;
        q_mass_.resize(0);  // M, V_m and G changed
        q_bias_.resize(0);
      }
    }
  }

  // Plant.load_torque: u + J(q)^T w of the held loads (zero without any)
  double load(int i) const { return load_.size() ? load_[i] : 0.0; }

  double stop_torque(int i, double q, double v) const {  // JointStops.torque
    if (!s.stops) return 0.0;
    const double pen = std::max(q - s.stop_upper[i], 0.0) + std::min(q - s.stop_lower[i], 0.0);
    if (pen == 0.0) return 0.0;
    const double sg = sign(pen);
    return -sg * std::max(s.stop_stiffness[i] * std::abs(pen) * (1.0 + s.stop_alpha * sg * v), 0.0);
  }

  // Plant.acceleration: the slipping law with sgn(0) = 0, net_torque with every mode sgn(v_i)
  Vector acceleration(double t, const Vector &q, const Vector &v, const Vector &tau) {
    signs_.resize(v.size());
    for (int i = 0; i < v.size(); ++i) signs_[i] = static_cast<int>(sign(v[i]));
    return pin::aba(m.model, m.data, q, v, net_torque(t, q, v, tau, signs_));
  }

  // Plant.net_torque: tau + tau_stop - tau_d - F, the sticky joints' dry friction F_c mode_i
  const Vector &net_torque(double t, const Vector &q, const Vector &v, const Vector &tau, const Modes &mode) {
    const int n = static_cast<int>(q.size());
    net_.resize(n);
    if (has_wrench_) loaded_ = load_ + m.frame_jacobian(q).transpose() * wrench_;
    for (int i = 0; i < n; ++i) {
      const double friction = sticky(i) ? s.viscous[i] * v[i] + s.coulomb[i] * mode[i]
                                        : s.viscous[i] * v[i] + s.coulomb[i] * sign(v[i]);
      net_[i] = tau[i] - friction - disturbance(i, t);
      if (has_wrench_) net_[i] += loaded_[i];
      else if (load_.size()) net_[i] += load_[i];
      net_[i] += stop_torque(i, q[i], v[i]);
    }
    return net_;
  }

  // M(q) with both triangles (PinocchioModel.mass); kept for the last q, since a step's end, the
  // next command's choice of modes and its first RK4 stage all ask at the same state
  const Matrix &mass(const Vector &q) {
    if (q_mass_.size() != q.size() || q_mass_ != q) {
      pin::crba(m.model, m.data, q);
      M_ = m.data.M;
      M_.triangularView<Eigen::StrictlyLower>() = M_.transpose();
      q_mass_ = q;
    }
    return M_;
  }

  // V_m(q, v) v + G(q) (PinocchioModel.bias), kept for the last (q, v) likewise
  const Vector &bias(const Vector &q, const Vector &v) {
    if (q_bias_.size() != q.size() || q_bias_ != q || v_bias_ != v) {
      bias_ = pin::nonLinearEffects(m.model, m.data, q, v);
      q_bias_ = q;
      v_bias_ = v;
    }
    return bias_;
  }

  // Plant.constrained_acceleration: q'' with the held joints' q''_i = 0, and `hold`, the
  // friction torque holding them (in joint order)
  Vector constrained_acceleration(double t, const Vector &q, const Vector &v, const Vector &tau, const Modes &mode,
                                  Vector &hold) {
    const int n = static_cast<int>(q.size());
    net_torque(t, q, v, tau, mode);
    free_.clear();
    held_.clear();
    for (int i = 0; i < n; ++i) (sticky(i) && mode[i] == 0 ? held_ : free_).push_back(i);
    if (held_.empty()) {
      hold.resize(0);
      return pin::aba(m.model, m.data, q, v, net_);
    }
    mass(q);
    r_ = net_ - bias(q, v);
    Vector a = Vector::Zero(n);
    const int nf = static_cast<int>(free_.size());
    if (nf) {
      Mff_.resize(nf, nf);
      rf_.resize(nf);
      for (int i = 0; i < nf; ++i) {
        rf_[i] = r_[free_[i]];
        for (int j = 0; j < nf; ++j) Mff_(i, j) = M_(free_[i], free_[j]);
      }
      llt_.compute(Mff_);
      rf_ = llt_.solve(rf_);
      for (int i = 0; i < nf; ++i) a[free_[i]] = rf_[i];
    }
    const int nh = static_cast<int>(held_.size());
    hold.resize(nh);
    for (int i = 0; i < nh; ++i) hold[i] = r_[held_[i]] - M_.row(held_[i]).dot(a);
    return a;
  }

 private:
  // workspaces: sized once, so a step allocates nothing here
  Vector net_, r_, rf_, dist_;
  Vector load_, wrench_, loaded_;  // begin_period's held loads; loaded_: with J^T w
  bool has_wrench_ = false;
  int payload_index_ = -1;
  double dist_t_ = std::numeric_limits<double>::quiet_NaN();
  Matrix M_, Mff_;
  Vector q_mass_, q_bias_, v_bias_, bias_;
  Eigen::LLT<Matrix> llt_;
  std::vector<int> free_, held_;
  Modes signs_;
};

}  // namespace nnrobust
