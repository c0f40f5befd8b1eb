// The robot model on the C++ side: exactly the Pinocchio model Python built (locked joints,
// perturbed inertias, armature, gravity), rebuilt joint by joint from its numbers.
#pragma once

#include <string>
#include <vector>

#include <pinocchio/multibody/data.hpp>
#include <pinocchio/multibody/model.hpp>

namespace nnrobust {

using Vector = Eigen::VectorXd;
using Matrix = Eigen::MatrixXd;

// A Pinocchio model as the numbers that its dynamics and kinematics read (nnrobust/compiled.py,
// model_spec), so that the C++ side builds exactly the model Python built without Pinocchio's
// serialization (which cost the unit that used it 0.9 GB of compiler memory). Joint i + 1 has the
// type joint_types[i] (pin's shortname: "JointModelRZ", ..., the unaligned ones with axes row i),
// the parent parents[i], and the placement rotations rows 3i..3i+2 with translations row i in
// that parent; it carries inertias row i: mass, lever (3), then the rotational inertia about the
// centre of mass row by row (9). The task frame sits on joint frame_joint at frame_rotation,
// frame_translation.
struct ModelSpec {
  std::vector<std::string> joint_types, joint_names;
  std::vector<int> parents;
  Matrix axes, rotations, translations, inertias;  // J x 3, 3J x 3, J x 3, J x 13
  Vector armature;                                  // nv
  Eigen::Vector3d gravity = Eigen::Vector3d::Zero();
  std::string frame_name;
  int frame_joint = 0;
  Eigen::Matrix3d frame_rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d frame_translation = Eigen::Vector3d::Zero();
};

struct LoadedModel {
  pinocchio::Model model;
  pinocchio::Data data;
  pinocchio::FrameIndex frame;

  explicit LoadedModel(const ModelSpec &spec);

  int nq() const { return model.nq; }
  Matrix mass(const Vector &q);                    // M(q), both triangles filled
  Vector bias(const Vector &q, const Vector &v);   // V_m(q, v) v + G(q), by RNEA at zero acceleration
  Matrix frame_jacobian(const Vector &q);         // 6 x n, world-aligned axes at the frame's origin
};


}  // namespace nnrobust
