// The bare C++ closed loop that the compiled backend is measured against: per 1 ms control step,
// one RNEA (the controller's M-hat a + N-hat), one frame-kinematics pass (x, J, J'q') and four ABA
// calls (RK4 of the plant, torque held). It controls nothing useful; it is the cost floor of a step.
// A benchmark target (benchmarks/closed_loop.py), built as its own module, nnrobust._floor_loop,
// outside the product module nnrobust._loop; it takes the LoadedModel that _loop builds.
#include <nanobind/eigen/dense.h>
#include <nanobind/nanobind.h>

#include "../csrc/model/model.hpp"
#include "../csrc/pin_calls.hpp"

namespace nnrobust {
namespace {

// Returns the final [q, v] after `steps` control steps of length `dt`.
Vector floor_loop(LoadedModel &m, const Vector &q0, const Vector &v0, long steps, double dt) {
  const int n = m.model.nv;
  Vector q = q0, v = v0, a = Vector::Zero(n), tau(n);
  pin::Matrix6x J = pin::Matrix6x::Zero(6, n);
  auto &model = m.model;
  auto &data = m.data;
  auto acc = [&](const Vector &qs, const Vector &vs) -> Vector {
    return pin::aba(model, data, qs, vs, tau);
  };
  for (long k = 0; k < steps; ++k) {
    pin::forwardKinematics(model, data, q, v, a);
    pin::updateFramePlacement(model, data, m.frame);
    pin::computeJointJacobians(model, data);
    pin::getFrameJacobian(model, data, m.frame, pinocchio::LOCAL_WORLD_ALIGNED, J);
    const Eigen::Vector3d jdot_v =
        pin::getFrameClassicalAcceleration(model, data, m.frame, pinocchio::LOCAL_WORLD_ALIGNED).linear();
    a = -0.01 * (J.topRows<3>().transpose() * jdot_v) - v;  // a cheap stand-in for the law
    tau = pin::rnea(model, data, q, v, a);
    // RK4 of (q, v)' = (v, ABA(q, v, tau)) with tau held
    const Vector k1q = v, k1v = acc(q, v);
    const Vector k2q = v + 0.5 * dt * k1v, k2v = acc(q + 0.5 * dt * k1q, k2q);
    const Vector k3q = v + 0.5 * dt * k2v, k3v = acc(q + 0.5 * dt * k2q, k3q);
    const Vector k4q = v + dt * k3v, k4v = acc(q + dt * k3q, k4q);
    q += (dt / 6.0) * (k1q + 2.0 * k2q + 2.0 * k3q + k4q);
    v += (dt / 6.0) * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
    a.setZero();
  }
  Vector out(2 * n);
  out << q, v;
  return out;
}

}  // namespace
}  // namespace nnrobust

NB_MODULE(_floor_loop, m) {
  namespace nb = nanobind;
  m.doc() = "The bare C++ loop that benchmarks/closed_loop.py measures the compiled loop against.";
  m.def("floor_loop", &nnrobust::floor_loop, nb::arg("model"), nb::arg("q0"), nb::arg("v0"), nb::arg("steps"),
        nb::arg("dt"), nb::call_guard<nb::gil_scoped_release>(),
        "RNEA + frame kinematics + 4 ABA per step on a nnrobust._loop.LoadedModel; returns the final [q, v].");
}
