// The robot model on the C++ side: exactly the Pinocchio model Python built (locked joints,
// perturbed inertias, gravity), received through Pinocchio's own serialization.
#pragma once

#include <string>

#include <pinocchio/multibody/data.hpp>
#include <pinocchio/multibody/model.hpp>

namespace nnrobust {

using Vector = Eigen::VectorXd;
using Matrix = Eigen::MatrixXd;

struct LoadedModel {
  pinocchio::Model model;
  pinocchio::Data data;
  pinocchio::FrameIndex frame;

  // `serialized`: pin.Model.saveToString(); `frame_name`: the task frame.
  LoadedModel(const std::string &serialized, const std::string &frame_name);

  int nq() const { return model.nq; }
  Matrix mass(const Vector &q);                    // M(q), both triangles filled
  Vector bias(const Vector &q, const Vector &v);   // V_m(q, v) v + G(q), by RNEA at zero acceleration
  Matrix frame_jacobian(const Vector &q);         // 6 x n, world-aligned axes at the frame's origin
};

// The bare loop of benchmarks/closed_loop.py (floor_loop.cpp); returns the final [q, v].
Vector floor_loop(LoadedModel &m, const Vector &q0, const Vector &v0, long steps, double dt);

}  // namespace nnrobust
