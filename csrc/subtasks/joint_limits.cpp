// Twins of nnrobust/subtasks/joint_limits.py: JointLimitAvoidance and JointCentering.
#include <algorithm>
#include <cmath>

#include "criterion.hpp"

namespace nnrobust {
namespace {

// h = -mean(b_i), b the barrier span^2 / (4 (u - q)(q - l)) continued linearly outside the
// knots l + margin span, u - margin span; a joint without limits has b = 1 (fields: lower,
// upper, margin)
struct JointLimitAvoidance : Criterion {
  Vector lower, upper;
  double margin;
  mutable Vector b_, db_;  // value's barrier, sized here: a recorded step allocates nothing
  explicit JointLimitAvoidance(const Fields &f)
      : lower(f.vector("lower")), upper(f.vector("upper")), margin(f.scalar("margin")),
        b_(Vector::Zero(lower.size())), db_(Vector::Zero(lower.size())) {}

  void barrier(const Vector &q, Vector &b, Vector &db) const {
    b.resize(q.size());
    db.resize(q.size());
    for (int i = 0; i < q.size(); ++i) {
      const double span = upper[i] - lower[i];
      if (!std::isfinite(span)) {
        b[i] = 1.0;
        db[i] = 0.0;
        continue;
      }
      const double knot = std::clamp(q[i], lower[i] + margin * span, upper[i] - margin * span);
      const double g = (upper[i] - knot) * (knot - lower[i]);
      db[i] = -span * span * (upper[i] + lower[i] - 2 * knot) / (4 * g * g);
      b[i] = span * span / (4 * g) + db[i] * (q[i] - knot);
    }
  }
  double value(const Vector &q, double, const Matrix &) const override {
    barrier(q, b_, db_);
    return -b_.mean();
  }
  Vector gradient(const Vector &q, DetAtQ &) const override {
    Vector b, db;
    barrier(q, b, db);
    return -db / static_cast<double>(q.size());
  }
};

// h = -(1/2n) sum ((q - c) / (u - l))^2, c the mid-range; no term for a joint without limits
// (fields: lower, upper)
struct JointCentering : Criterion {
  Vector lower, upper;
  explicit JointCentering(const Fields &f) : lower(f.vector("lower")), upper(f.vector("upper")) {}

  Vector centered(const Vector &q) const {
    Vector c(q.size());
    for (int i = 0; i < q.size(); ++i) {
      const double span = upper[i] - lower[i];
      c[i] = std::isfinite(span) ? (q[i] - 0.5 * (lower[i] + upper[i])) / span : 0.0;
    }
    return c;
  }
  double value(const Vector &q, double, const Matrix &) const override {
    return -0.5 * centered(q).squaredNorm() / static_cast<double>(q.size());
  }
  Vector gradient(const Vector &q, DetAtQ &) const override {
    return -centered(q).cwiseQuotient(upper - lower) / static_cast<double>(q.size());
  }
};

}  // namespace
NNROBUST_CRITERION("joint_limits", JointLimitAvoidance);
NNROBUST_CRITERION("joint_centering", JointCentering);
}  // namespace nnrobust
