// The self-motion criteria on the C++ side: the twins of nnrobust/subtasks (WeightedCriteria over
// the shipped criteria), named by LoopSpec.criteria.
#pragma once

#include <vector>

#include "nominal.hpp"

namespace nnrobust {

// SphereObstacles._pairs for every (segment, obstacle): t, the unit normal and the clearance d
struct ObstaclePair {
  int segment;
  double t, depth;
  Vector3d normal;
};

std::vector<ObstaclePair> obstacle_pairs(const LoopSpec &s, const Matrix &points);

// The shipped criteria, named in LoopSpec.criteria (resolved once, not compared per step).
enum class CriterionKind { paper, half_det, manipulability, joint_limits, joint_centering, joint_smoothness, obstacles };

struct Criteria {
  const LoopSpec &s;
  std::vector<CriterionKind> kinds;  // s.criteria's names, resolved

  explicit Criteria(const LoopSpec &spec);  // an unknown name is refused (std::invalid_argument)

  // JointLimitAvoidance._barrier: (b, b') with the linear continuation outside the knots; a joint
  // without limits (a continuous joint) has b = 1, b' = 0
  void barrier(const Vector &q, Vector &b, Vector &db) const;
  // JointCentering: (q - c) / (u - l), c the mid-range; 0 for a joint without limits
  Vector centered(const Vector &q) const;
  // WeightedCriteria.gradient on the nominal model (ts: its task state at q)
  Vector gradient(Nominal &model, const Vector &q, const TaskState &ts) const;
  // WeightedCriteria.value on the true robot (J: its task Jacobian at q, points: its chain)
  double value(const Vector &q, const Matrix &J, const Matrix &points) const;
};

}  // namespace nnrobust
