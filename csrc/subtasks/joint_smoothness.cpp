// Twins of nnrobust/subtasks/joint_smoothness.py: JointSmoothness and the paper's eq. (19).
#include "criterion.hpp"

namespace nnrobust {
namespace {

// h = -0.5 (c^T q)^2 (fields: coefficients c)
struct JointSmoothness : Criterion {
  Vector c;
  explicit JointSmoothness(const Fields &f) : c(f.vector("coefficients")) {}
  double value(const Vector &q, double, const Matrix &) const override {
    const double cq = c.dot(q);
    return -0.5 * cq * cq;
  }
  Vector gradient(const Vector &q, DetAtQ &) const override { return -c.dot(q) * c; }
};

// eq. (19): h = 0.5 det(J J^T) - 0.5 (c^T q)^2 (fields: coefficients c = (0.5, -1, 1))
struct PaperCriterion : Criterion {
  JointSmoothness smoothness;
  explicit PaperCriterion(const Fields &f) : smoothness(f) {}
  double value(const Vector &q, double det, const Matrix &points) const override {
    return 0.5 * det + smoothness.value(q, det, points);
  }
  Vector gradient(const Vector &q, DetAtQ &d) const override {
    d.need();
    return 0.5 * d.gradient + smoothness.gradient(q, d);
  }
};

}  // namespace
NNROBUST_CRITERION("joint_smoothness", JointSmoothness);
NNROBUST_CRITERION("paper", PaperCriterion);
}  // namespace nnrobust
