// MuJoCo stepping the plant: the twin of nnrobust/plant/mujoco_engine.py's MujocoPlant.advance,
// built from its twin_fields: the addresses of mj_step, the mjModel and mjData and of qpos, qvel,
// ctrl and qfrc_applied inside the data (each a whole number below 2^53, exact as a double; the
// caller keeps them alive for the run and resets the state to q0, v0), of the counts of the warnings
// on which MuJoCo resets a bad state or zeroes a bad command (BAD_STATE_WARNINGS), and joint i's place
// in qpos and qvel. No MuJoCo header is needed: mj_step(const mjModel*, mjData*) is the only call.
#pragma once

#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "../fields.hpp"
#include "disturbance.hpp"

namespace nnrobust {

struct MujocoPlant {
  using Step = void (*)(const void *, void *);
  Step step;
  const void *model;
  void *data;
  const double *qpos, *qvel;
  double *ctrl, *qfrc_applied;
  const int *warned[4];  // mjData's warning[mjWARN_BADQPOS, BADQVEL, BADQACC, BADCTRL].number
  std::vector<int> qpos_index, dof_index;
  int substeps;

  explicit MujocoPlant(const Fields &f)
      : step(reinterpret_cast<Step>(address(f, "step"))), model(reinterpret_cast<const void *>(address(f, "model"))),
        data(reinterpret_cast<void *>(address(f, "data"))), qpos(reinterpret_cast<const double *>(address(f, "qpos"))),
        qvel(reinterpret_cast<const double *>(address(f, "qvel"))), ctrl(reinterpret_cast<double *>(address(f, "ctrl"))),
        qfrc_applied(reinterpret_cast<double *>(address(f, "qfrc_applied"))),
        warned{reinterpret_cast<const int *>(address(f, "warned_position")),
               reinterpret_cast<const int *>(address(f, "warned_velocity")),
               reinterpret_cast<const int *>(address(f, "warned_acceleration")),
               reinterpret_cast<const int *>(address(f, "warned_control"))},
        qpos_index(indices(f, "qpos_index")), dof_index(indices(f, "dof_index")),
        substeps(static_cast<int>(f.scalar("substeps"))) {}

  // MujocoPlant.advance: MuJoCo's substeps over one control period with tau held, -tau_d + the held
  // joint load at each mid-step; (q, q') read back. False when MuJoCo found a bad position, velocity,
  // acceleration or torque command and reset the state or zeroed the command (the run ends;
  // MujocoPlant.failure names it)
  template <class Load>
  bool advance(double t, const Vector &tau, double period, Disturbance &disturbance, const Load &load,
               Vector &q, Vector &v) const {
    const int n = static_cast<int>(tau.size());
    const double h = period / substeps;
    for (int i = 0; i < n; ++i) ctrl[i] = tau[i];
    for (int j = 0; j < substeps; ++j) {
      const Vector &d = disturbance(t + (j + 0.5) * h);
      for (int i = 0; i < n; ++i) qfrc_applied[dof_index[i]] = -d[i] + load(i);
      step(model, data);
      if (*warned[0] || *warned[1] || *warned[2] || *warned[3]) return false;
    }
    for (int i = 0; i < n; ++i) {
      q[i] = qpos[qpos_index[i]];
      v[i] = qvel[dof_index[i]];
    }
    return true;
  }

 private:
  static std::uintptr_t address(const Fields &f, const char *name) {
    const double x = f.scalar(name);
    if (!(x > 0 && x < 9007199254740992.0 && x == std::floor(x)))
      throw std::invalid_argument(f.owner + ": the field " + std::string(name) + " is not an address");
    return static_cast<std::uintptr_t>(x);
  }
  static std::vector<int> indices(const Fields &f, const char *name) {
    const Vector x = f.vector(name);
    return std::vector<int>(x.data(), x.data() + x.size());
  }
};

}  // namespace nnrobust
