// Twins of nnrobust/subtasks/manipulability.py: HalfDetManipulability and Manipulability.
#include <cmath>

#include "criterion.hpp"

namespace nnrobust {
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
