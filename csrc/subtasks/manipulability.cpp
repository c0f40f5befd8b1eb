// Twins of nnrobust/subtasks/manipulability.py: HalfDetManipulability and Manipulability.
#include <cmath>

#include "criterion.hpp"
#include "manipulability.hpp"

namespace nnrobust {

// manipulability.det and manipulability.adjugate (manipulability.hpp)
double det_small(const Matrix &A) {
  if (A.rows() == 1) return A(0, 0);
  if (A.rows() == 2) return A(0, 0) * A(1, 1) - A(0, 1) * A(1, 0);
  if (A.rows() > 3) return A.determinant();
  const Eigen::Vector3d a0 = A.col(0), a1 = A.col(1), a2 = A.col(2);
  return a0.dot(a1.cross(a2));
}

Matrix adjugate_small(const Matrix &A) {
  Matrix adj(A.rows(), A.cols());
  if (A.rows() == 1) {
    adj(0, 0) = 1.0;
  } else if (A.rows() == 2) {
    adj << A(1, 1), -A(0, 1), -A(1, 0), A(0, 0);
  } else {
    const Eigen::Vector3d a0 = A.col(0), a1 = A.col(1), a2 = A.col(2);
    adj.row(0) = a1.cross(a2).transpose();
    adj.row(1) = a2.cross(a0).transpose();
    adj.row(2) = a0.cross(a1).transpose();
  }
  return adj;
}

namespace {

// h = 0.5 det(J J^T)
struct HalfDetManipulability : Criterion {
  explicit HalfDetManipulability(const Fields &) {}
  double value(const Vector &, double det, const Matrix &) const override { return 0.5 * det; }
  Vector gradient(const Vector &, DetAtQ &d) const override {
    d.need();
    return 0.5 * d.gradient;
  }
};

// h = sqrt(det(J J^T)) (Yoshikawa); its gradient is 0 where det vanishes
struct Manipulability : Criterion {
  explicit Manipulability(const Fields &) {}
  double value(const Vector &, double det, const Matrix &) const override { return std::sqrt(std::max(det, 0.0)); }
  Vector gradient(const Vector &q, DetAtQ &d) const override {
    d.need();
    return d.det <= 1e-300 ? Vector(Vector::Zero(q.size())) : Vector(d.gradient / (2.0 * std::sqrt(d.det)));
  }
};

}  // namespace
NNROBUST_CRITERION("half_det_manipulability", HalfDetManipulability);
NNROBUST_CRITERION("manipulability", Manipulability);
}  // namespace nnrobust
