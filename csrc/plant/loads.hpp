// The loads of [[plant.loads]] that switch on and off during a run: the twin of
// nnrobust/plant/loads.py's ExternalLoads, built from its twin_fields (torque pulses u over
// [start, end), tool wrenches w over [start, end) in world axes at the task frame, payload
// changes at start).
#pragma once

#include "../fields.hpp"

namespace nnrobust {

struct ExternalLoads {
  Vector pulse_start, pulse_end, wrench_start, wrench_end, payload_start;  // [s]: P, P, W, W, C
  Matrix pulse_torque, wrench;                                             // n x P [N m], 6 x W [N, N m]

  explicit ExternalLoads(const Fields &f)
      : pulse_start(f.vector("pulse_start")), pulse_end(f.vector("pulse_end")),
        wrench_start(f.vector("wrench_start")), wrench_end(f.vector("wrench_end")),
        payload_start(f.vector("payload_start")), pulse_torque(f.matrix("pulse_torque")), wrench(f.matrix("wrench")) {}

  // ExternalLoads.at: the joint torque and the wrench (`has_wrench` false: none) held over the
  // control period that starts at t
  void at(double t, Vector &torque, Vector &w, bool &has_wrench) const {
    torque.setZero(pulse_torque.rows());
    for (Eigen::Index p = 0; p < pulse_start.size(); ++p)
      if (pulse_start[p] <= t && t < pulse_end[p]) torque += pulse_torque.col(p);
    w.setZero(6);
    has_wrench = false;
    for (Eigen::Index k = 0; k < wrench_start.size(); ++k)
      if (wrench_start[k] <= t && t < wrench_end[k]) {
        w += wrench.col(k);
        has_wrench = true;
      }
  }

  // the payload changes made by t (sorted by start)
  int payloads_carried(double t) const {
    int carried = 0;
    for (Eigen::Index c = 0; c < payload_start.size(); ++c) carried += payload_start[c] <= t;
    return carried;
  }
};

}  // namespace nnrobust
