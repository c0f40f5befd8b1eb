// Pinocchio's algorithms, called with exactly the argument types that the pin wheel's library
// (libpinocchio_default) instantiates. With PINOCCHIO_ENABLE_TEMPLATE_INSTANTIATION, Pinocchio
// declares those instantiations `extern template`: a call that matches one links to the library,
// one that does not (aba with a plain VectorXd, a Jacobian into a MatrixXd) makes the compiler
// instantiate the whole algorithm over every joint type again. One such call costs about 1.9 GB
// of compiler memory; closed_loop.cpp needed 4 GB before every call went through here.
#pragma once

#include <pinocchio/algorithm/aba.hpp>
#include <pinocchio/algorithm/crba.hpp>
#include <pinocchio/algorithm/frames.hpp>
#include <pinocchio/algorithm/jacobian.hpp>
#include <pinocchio/algorithm/kinematics.hpp>
#include <pinocchio/algorithm/rnea.hpp>

namespace nnrobust::pin {

using Model = pinocchio::Model;
using Data = pinocchio::Data;
using Vec = Eigen::VectorXd;
using CRef = Eigen::Ref<const Vec>;
using Matrix6x = Data::Matrix6x;  // 6 x n

// Forward dynamics q'' = ABA(q, q', tau).
inline const Vec &aba(const Model &m, Data &d, CRef q, CRef v, CRef tau) {
  return pinocchio::aba<double, 0, pinocchio::JointCollectionDefaultTpl, CRef, CRef, CRef>(
      m, d, q, v, tau, pinocchio::Convention::LOCAL);
}

// M(q) into d.M (upper triangle).
inline const Eigen::MatrixXd &crba(const Model &m, Data &d, CRef q) {
  return pinocchio::crba<double, 0, pinocchio::JointCollectionDefaultTpl, CRef>(m, d, q,
                                                                                pinocchio::Convention::LOCAL);
}

// M(q) a + V_m(q, q') q' + G(q).
inline const Vec &rnea(const Model &m, Data &d, CRef q, CRef v, CRef a) {
  return pinocchio::impl::rnea<double, 0, pinocchio::JointCollectionDefaultTpl, CRef, CRef, CRef>(m, d, q, v, a);
}

// V_m(q, q') q' + G(q).
inline const Vec &nonLinearEffects(const Model &m, Data &d, CRef q, CRef v) {
  return pinocchio::impl::nonLinearEffects<double, 0, pinocchio::JointCollectionDefaultTpl, CRef, CRef>(m, d, q, v);
}

// G(q).
inline const Vec &computeGeneralizedGravity(const Model &m, Data &d, CRef q) {
  return pinocchio::impl::computeGeneralizedGravity<double, 0, pinocchio::JointCollectionDefaultTpl, CRef>(m, d, q);
}

// Placements, velocities and accelerations of every joint.
inline void forwardKinematics(const Model &m, Data &d, CRef q, CRef v, CRef a) {
  pinocchio::impl::forwardKinematics<double, 0, pinocchio::JointCollectionDefaultTpl, CRef, CRef, CRef>(m, d, q, v, a);
}

// Placements and world-frame Jacobians of every joint, at q.
inline const Matrix6x &computeJointJacobians(const Model &m, Data &d, CRef q) {
  return pinocchio::impl::computeJointJacobians<double, 0, pinocchio::JointCollectionDefaultTpl, CRef>(m, d, q);
}

// The same, from the placements forwardKinematics left in d.
inline const Matrix6x &computeJointJacobians(const Model &m, Data &d) {
  return pinocchio::computeJointJacobians<double, 0, pinocchio::JointCollectionDefaultTpl>(m, d);
}

inline const pinocchio::SE3 &updateFramePlacement(const Model &m, Data &d, pinocchio::FrameIndex frame) {
  return pinocchio::updateFramePlacement<double, 0, pinocchio::JointCollectionDefaultTpl>(m, d, frame);
}

inline pinocchio::Motion getFrameClassicalAcceleration(const Model &m, const Data &d, pinocchio::FrameIndex frame,
                                                       pinocchio::ReferenceFrame rf) {
  return pinocchio::getFrameClassicalAcceleration<double, 0, pinocchio::JointCollectionDefaultTpl>(m, d, frame, rf);
}

// A frame's 6 x n Jacobian from the joint Jacobians in d.
inline void getFrameJacobian(const Model &m, Data &d, pinocchio::FrameIndex frame, pinocchio::ReferenceFrame rf,
                             Matrix6x &J) {
  pinocchio::getFrameJacobian<double, 0, pinocchio::JointCollectionDefaultTpl, Matrix6x>(m, d, frame, rf, J);
}

// A joint's 6 x n Jacobian from the joint Jacobians in d.
inline void getJointJacobian(const Model &m, const Data &d, pinocchio::JointIndex joint, pinocchio::ReferenceFrame rf,
                             Matrix6x &J) {
  Eigen::Ref<Matrix6x> out(J);
  pinocchio::impl::getJointJacobian<double, 0, pinocchio::JointCollectionDefaultTpl, Eigen::Ref<Matrix6x>>(
      m, d, joint, rf, out);
}

// A frame's 6 x n Jacobian at q: the joint Jacobians, then the frame's (two calls the library
// instantiates; pinocchio::computeFrameJacobian with these types is not, and instantiating it cost
// every unit that includes this header 0.75 GB of compiler memory).
inline void computeFrameJacobian(const Model &m, Data &d, const Vec &q, pinocchio::FrameIndex frame,
                                 pinocchio::ReferenceFrame rf, Matrix6x &J) {
  computeJointJacobians(m, d, q);
  getFrameJacobian(m, d, frame, rf, J);
}

}  // namespace nnrobust::pin
