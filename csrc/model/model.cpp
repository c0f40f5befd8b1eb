#include "model.hpp"

#include <stdexcept>

#include "../pin_calls.hpp"

namespace nnrobust {

namespace {

pinocchio::SE3 placement(const Eigen::Matrix3d &rotation, const Eigen::Vector3d &translation) {
  return pinocchio::SE3(rotation, translation);
}

// The joint of pin's shortname `type` (the unaligned ones about `axis`); another type is refused.
pinocchio::JointModel joint_model(const std::string &type, const Eigen::Vector3d &axis) {
  using namespace pinocchio;
  if (type == "JointModelRX") return JointModelRX();
  if (type == "JointModelRY") return JointModelRY();
  if (type == "JointModelRZ") return JointModelRZ();
  if (type == "JointModelPX") return JointModelPX();
  if (type == "JointModelPY") return JointModelPY();
  if (type == "JointModelPZ") return JointModelPZ();
  if (type == "JointModelRUBX") return JointModelRUBX();
  if (type == "JointModelRUBY") return JointModelRUBY();
  if (type == "JointModelRUBZ") return JointModelRUBZ();
  if (type == "JointModelRevoluteUnaligned") return JointModelRevoluteUnaligned(axis);
  if (type == "JointModelPrismaticUnaligned") return JointModelPrismaticUnaligned(axis);
  if (type == "JointModelRevoluteUnboundedUnaligned") return JointModelRevoluteUnboundedUnaligned(axis);
  throw std::invalid_argument("a joint of type " + type + " has no compiled twin");
}

}  // namespace

LoadedModel::LoadedModel(const ModelSpec &s) {
  const int joints = static_cast<int>(s.joint_types.size());
  if (static_cast<int>(s.parents.size()) != joints || static_cast<int>(s.joint_names.size()) != joints ||
      s.axes.rows() != joints || s.rotations.rows() != 3 * joints || s.translations.rows() != joints ||
      s.inertias.rows() != joints || s.inertias.cols() != 13)
    throw std::invalid_argument("ModelSpec: the joint arrays disagree in length");
  for (int i = 0; i < joints; ++i) {
    const Eigen::Vector3d axis = s.axes.row(i).transpose();
    const Eigen::Matrix3d rotation = s.rotations.middleRows(3 * i, 3);
    const Eigen::Vector3d translation = s.translations.row(i).transpose();
    const auto id = model.addJoint(s.parents[i], joint_model(s.joint_types[i], axis),
                                   placement(rotation, translation), s.joint_names[i]);
    const Eigen::Vector3d lever = s.inertias.block<1, 3>(i, 1).transpose();
    Eigen::Matrix3d rotational;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) rotational(r, c) = s.inertias(i, 4 + 3 * r + c);
    model.inertias[id] = pinocchio::Inertia(s.inertias(i, 0), lever, pinocchio::Symmetric3(rotational));
  }
  if (s.armature.size() != model.nv) throw std::invalid_argument("ModelSpec: armature needs one entry per velocity");
  model.armature = s.armature;
  model.gravity.linear(s.gravity);
  // append_inertia false: adding the frame's zero inertia to its joint's would recompute that
  // joint's centre of mass and move it by an ulp
  const pinocchio::SE3 at = placement(s.frame_rotation, s.frame_translation);
  frame = model.addFrame(pinocchio::Frame(s.frame_name, s.frame_joint, at, pinocchio::OP_FRAME), false);
  data = pinocchio::Data(model);
}

Matrix LoadedModel::mass(const Vector &q) {
  pin::crba(model, data, q);
  data.M.triangularView<Eigen::StrictlyLower>() = data.M.transpose().triangularView<Eigen::StrictlyLower>();
  return data.M;
}

Vector LoadedModel::bias(const Vector &q, const Vector &v) {
  return pin::rnea(model, data, q, v, Vector::Zero(model.nv));
}

Matrix LoadedModel::frame_jacobian(const Vector &q) {
  pin::Matrix6x J = pin::Matrix6x::Zero(6, model.nv);
  pin::computeFrameJacobian(model, data, q, frame, pinocchio::LOCAL_WORLD_ALIGNED, J);
  return J;
}

}  // namespace nnrobust
