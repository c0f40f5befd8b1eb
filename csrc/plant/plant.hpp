// The true robot: the twin of nnrobust/plant/plant.py, built from Plant.twin_fields (saturation,
// delay, the payload's joint and inertias) and its parts' (LoopSpec.plant_parts: friction,
// disturbance, loads, sensor, and stops and engine where there are some), each in the file named
// like its Python module. Included by closed_loop.cpp only.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Cholesky>

#include "../closed_loop.hpp"
#include "../per_size.hpp"
#include "../pin_calls.hpp"
#include "disturbance.hpp"
#include "friction.hpp"
#include "limits.hpp"
#include "loads.hpp"
#include "mujoco_engine.hpp"
#include "sensing.hpp"

namespace nnrobust {

using Modes = Eigen::VectorXi;  // per joint: +1 / -1 slipping, 0 held (nnrobust.plant.stick_slip)

// One part's fields (`optional`: a missing part is none, else an error naming it)
inline const Params *plant_part(const LoopSpec &s, const std::string &name, bool optional = false) {
  const auto it = s.plant_parts.find(name);
  if (it != s.plant_parts.end()) return &it->second;
  if (optional) return nullptr;
  throw std::invalid_argument("LoopSpec.plant_parts needs the part " + name + " (Plant.twin_parts)");
}

template <class Part>
std::optional<Part> optional_part(const LoopSpec &s, const std::string &name) {
  const Params *fields = plant_part(s, name, true);
  if (!fields) return std::nullopt;
  return Part(Fields{"the plant's " + name, *fields});
}

struct Plant {
  LoadedModel &m;
  Friction friction;
  std::unique_ptr<Disturbance> disturbance;  // registered under LoopSpec.disturbance
  ExternalLoads loads;
  Sensor sensor;
  std::optional<JointStops> stops;
  std::optional<MujocoPlant> engine;
  Vector effort_limit;  // the actuators' torque limits (inf: none)
  Vector speed_limit;   // the torque-speed envelope's velocity limits (inf: none)
  double knee;          // the envelope's knee, a fraction of speed_limit (< 0: no envelope)
  int delay;            // control periods between a measurement and its torque
  int payload_joint;    // the joint whose inertia a payload change sets
  Matrix payload_parameters;  // 10 x (C + 1): the inertias (pin.Inertia.toDynamicParameters) after each change, then before any

  Plant(LoadedModel &model, const LoopSpec &s)
      : m(model), friction(Fields{"the plant's friction", *plant_part(s, "friction")}),
        loads(Fields{"the plant's loads", *plant_part(s, "loads")}),
        sensor(Fields{"the plant's sensor", *plant_part(s, "sensor")}),
        stops(optional_part<JointStops>(s, "stops")), engine(optional_part<MujocoPlant>(s, "engine")) {
    const auto make_disturbance = DisturbanceRegistry::find(s.disturbance);
    if (!make_disturbance) throw std::invalid_argument("LoopSpec.disturbance: unknown disturbance " + s.disturbance);
    disturbance = make_disturbance(Fields{"the plant's disturbance " + s.disturbance, *plant_part(s, "disturbance")});
    const Fields own{"the plant", s.plant_params};
    effort_limit = own.vector("effort_limit");
    speed_limit = own.vector("envelope_speed_limit");
    knee = own.scalar("torque_speed_knee");
    delay = static_cast<int>(own.scalar("delay"));
    payload_joint = static_cast<int>(own.scalar("payload_joint"));
    payload_parameters = own.matrix("payload_parameters");
    load_ = Vector::Zero(m.model.nv);
  }

  bool sticky(int i) const { return friction.sticky(i); }  // Plant.sticky
  bool any_sticky() const {
    for (int i = 0; i < friction.stiction.size(); ++i)
      if (sticky(i)) return true;
    return false;
  }

  // Plant.applied_torque: the command saturated at the effort limits and, where set, the
  // torque-speed envelope at the joint speeds v, written into `out` (no allocation once sized)
  void applied_torque(const Vector &tau_cmd, const Vector &v, Vector &out) const {
    if (knee < 0.0) {
      saturate(tau_cmd, effort_limit, out);
      return;
    }
    out.resize(tau_cmd.size());
    for (Eigen::Index i = 0; i < tau_cmd.size(); ++i) {
      const double limit = available_torque(effort_limit[i], tau_cmd[i], v[i], speed_limit[i], knee);
      out[i] = std::clamp(tau_cmd[i], -limit, limit);
    }
  }

  // Plant.begin_period: the loads of [[plant.loads]] held over the control period that starts at t
  // (the joint torque and the tool wrench; the payload's inertia set on its joint)
  void begin_period(double t) {
    loads.at(t, load_, wrench_, has_wrench_);
    const int changes = static_cast<int>(loads.payload_start.size());
    if (changes) {
      const int carried = loads.payloads_carried(t);
      const int index = carried ? carried - 1 : changes;  // the last column: before any change
      if (index != payload_index_) {
        m.model.inertias[payload_joint] = pinocchio::Inertia::FromDynamicParameters(payload_parameters.col(index));
        payload_index_ = index;
        q_mass_.resize(0);  // M, V_m and G changed
        q_bias_.resize(0);
      }
    }
  }

  // Plant.load_torque's joint-torque part (the held pulses), joint i
  double load(int i) const { return load_.size() ? load_[i] : 0.0; }

  // the plant step's rate (simulation.step_rate): the fastest joint's speed, or the ring
  // frequency of a stop a joint is at or would reach within the period, whichever is higher
  double step_rate(const Vector &q, const Vector &v, double period) const {
    const double rate = v.cwiseAbs().maxCoeff();
    return stops ? std::max(rate, stops->ringing(q, v, period)) : rate;
  }

  // Plant.acceleration: the slipping law with sgn(0) = 0, net_torque with every mode sgn(v_i);
  // Pinocchio's buffer, good until the next call
  const Vector &acceleration(double t, const Vector &q, const Vector &v, const Vector &tau) {
    signs_.resize(v.size());
    for (int i = 0; i < v.size(); ++i) signs_[i] = static_cast<int>(sign(v[i]));
    return pin::aba(m.model, m.data, q, v, net_torque(t, q, v, tau, signs_));
  }

  // Plant.net_torque: tau + tau_stop - tau_d - F + the held loads, the sticky joints' dry
  // friction F_c mode_i
  const Vector &net_torque(double t, const Vector &q, const Vector &v, const Vector &tau, const Modes &mode) {
    const int n = static_cast<int>(q.size());
    net_.resize(n);
    if (has_wrench_) loaded_ = load_ + m.frame_jacobian(q).transpose() * wrench_;
    const Vector &d = (*disturbance)(t);
    for (int i = 0; i < n; ++i) {
      const double dry = sticky(i) ? friction.viscous[i] * v[i] + friction.coulomb[i] * mode[i]
                                   : friction.torque(i, v[i]);
      net_[i] = tau[i] - dry - d[i];
      net_[i] += has_wrench_ ? loaded_[i] : load_[i];
      if (stops) net_[i] += stops->torque(i, q[i], v[i]);
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

  // Plant.constrained_acceleration: q'' with the held joints' q''_i = 0, and `hold`'s first
  // entries, one per held joint, the friction torque holding them (in joint order; `hold` has n
  // entries, so that a change of modes never resizes it). The q'' returned is the plant's own
  // buffer (or Pinocchio's), good until the next call: a caller keeps a copy.
  const Vector &constrained_acceleration(double t, const Vector &q, const Vector &v, const Vector &tau,
                                         const Modes &mode, Vector &hold) {
    const int n = static_cast<int>(q.size());
    net_torque(t, q, v, tau, mode);
    free_.clear();
    held_.clear();
    for (int i = 0; i < n; ++i) (sticky(i) && mode[i] == 0 ? held_ : free_).push_back(i);
    if (hold.size() != n) hold.setZero(n);
    if (held_.empty()) return pin::aba(m.model, m.data, q, v, net_);
    mass(q);
    r_ = net_ - bias(q, v);
    Vector &a = constrained_;
    a.setZero(n);
    const int nf = static_cast<int>(free_.size());
    if (nf) {
      FreeBlock &b = free_blocks_.at(n, nf);
      for (int i = 0; i < nf; ++i) {
        b.r[i] = r_[free_[i]];
        for (int j = 0; j < nf; ++j) b.M(i, j) = M_(free_[i], free_[j]);
      }
      b.llt.compute(b.M);
      b.llt.solveInPlace(b.r);
      for (int i = 0; i < nf; ++i) a[free_[i]] = b.r[i];
    }
    const int nh = static_cast<int>(held_.size());
    for (int i = 0; i < nh; ++i) hold[i] = r_[held_[i]] - M_.row(held_[i]).dot(a);
    return a;
  }

 private:
  // constrained_acceleration's free block for nf free joints: M_ff, its right side and factor
  struct FreeBlock {
    Matrix M;
    Vector r;
    Eigen::LLT<Matrix> llt;
    explicit FreeBlock(int nf) : M(Matrix::Zero(nf, nf)), r(Vector::Zero(nf)), llt(nf) {}
  };
  PerSize<FreeBlock> free_blocks_;
  // workspaces: sized once, so a step allocates nothing here
  Vector net_, r_, constrained_;
  Vector load_, wrench_, loaded_;  // begin_period's held loads; loaded_: with J^T w
  bool has_wrench_ = false;
  int payload_index_ = -1;
  Matrix M_;
  Vector q_mass_, q_bias_, v_bias_, bias_;
  std::vector<int> free_, held_;
  Modes signs_;
};

}  // namespace nnrobust
