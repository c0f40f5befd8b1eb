// nnrobust._loop: the one binding module of the compiled backend (docs/compiled.md).
#include <nanobind/eigen/dense.h>
#include <nanobind/nanobind.h>
#include <nanobind/stl/string.h>

#include "model.hpp"

namespace nb = nanobind;
using nnrobust::LoadedModel;

NB_MODULE(_loop, m) {
  m.doc() = "The compiled closed loop of nnrobust (Pinocchio C++ API).";
  nb::class_<LoadedModel>(m, "LoadedModel", "A Pinocchio model received from Python by serialization.")
      .def(nb::init<const std::string &, const std::string &>(), nb::arg("serialized"), nb::arg("frame"))
      .def_prop_ro("nq", &LoadedModel::nq)
      .def("mass", &LoadedModel::mass, nb::arg("q"), "M(q) [kg m^2].")
      .def("bias", &LoadedModel::bias, nb::arg("q"), nb::arg("v"), "V_m(q, v) v + G(q) [N m].")
      .def("frame_jacobian", &LoadedModel::frame_jacobian, nb::arg("q"),
           "6 x n Jacobian of the task frame, world-aligned axes.");
  m.def("floor_loop", &nnrobust::floor_loop, nb::arg("model"), nb::arg("q0"), nb::arg("v0"),
        nb::arg("steps"), nb::arg("dt"), nb::call_guard<nb::gil_scoped_release>(),
        "The bare C++ loop (RNEA + frame kinematics + 4 ABA per step); returns the final [q, v].");
}
