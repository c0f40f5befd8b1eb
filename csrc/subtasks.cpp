#include "subtasks.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace nnrobust {

std::vector<ObstaclePair> obstacle_pairs(const LoopSpec &s, const Matrix &points) {
  std::vector<ObstaclePair> pairs;
  for (int seg = 0; seg + 1 < points.rows(); ++seg) {
    const Vector3d a = points.row(seg).transpose(), b = points.row(seg + 1).transpose(), ab = b - a;
    const double length2 = std::max(ab.squaredNorm(), 1e-300);
    for (int o = 0; o < s.obstacle_centers.rows(); ++o) {
      const Vector3d c = s.obstacle_centers.row(o).transpose();
      const double t = std::clamp((c - a).dot(ab) / length2, 0.0, 1.0);
      const Vector3d gap = c - (a + t * ab);
      const double dist = std::max(gap.norm(), 1e-12);
      const double d = dist - s.obstacle_radii[o] - s.link_radius;
      pairs.push_back({seg, t, std::max(0.0, s.obstacle_influence - d), gap / dist});
    }
  }
  return pairs;
}

Criteria::Criteria(const LoopSpec &spec) : s(spec) {
  const std::pair<const char *, CriterionKind> names[] = {
      {"paper", CriterionKind::paper},
      {"half_det", CriterionKind::half_det},
      {"manipulability", CriterionKind::manipulability},
      {"joint_limits", CriterionKind::joint_limits},
      {"joint_centering", CriterionKind::joint_centering},
      {"joint_smoothness", CriterionKind::joint_smoothness},
      {"obstacles", CriterionKind::obstacles},
  };
  for (const std::string &name : spec.criteria) {
    const auto *found = std::find_if(std::begin(names), std::end(names), [&](const auto &p) { return name == p.first; });
    if (found == std::end(names)) throw std::invalid_argument("LoopSpec.criteria: unknown criterion " + name);
    kinds.push_back(found->second);
  }
}

// JointLimitAvoidance._barrier
void Criteria::barrier(const Vector &q, Vector &b, Vector &db) const {
  const Vector span = s.limit_upper - s.limit_lower;
  b.resize(q.size());
  db.resize(q.size());
  for (int i = 0; i < q.size(); ++i) {
    if (!std::isfinite(span[i])) {
      b[i] = 1.0;
      db[i] = 0.0;
      continue;
    }
    const double lo = s.limit_lower[i] + s.limit_margin * span[i], hi = s.limit_upper[i] - s.limit_margin * span[i];
    const double knot = std::clamp(q[i], lo, hi);
    const double g = (s.limit_upper[i] - knot) * (knot - s.limit_lower[i]);
    const double bi = span[i] * span[i] / (4 * g);
    db[i] = -span[i] * span[i] * (s.limit_upper[i] + s.limit_lower[i] - 2 * knot) / (4 * g * g);
    b[i] = bi + db[i] * (q[i] - knot);
  }
}

// JointCentering's (q - c) / (u - l)
Vector Criteria::centered(const Vector &q) const {
  Vector c(q.size());
  for (int i = 0; i < q.size(); ++i) {
    const double span = s.limit_upper[i] - s.limit_lower[i];
    c[i] = std::isfinite(span) ? (q[i] - 0.5 * (s.limit_lower[i] + s.limit_upper[i])) / span : 0.0;
  }
  return c;
}

// WeightedCriteria.gradient
Vector Criteria::gradient(Nominal &model, const Vector &q, const TaskState &ts) const {
  const Matrix &J = ts.J;
  const int n = static_cast<int>(q.size());
  Vector grad = Vector::Zero(n);
  bool have_det = false;
  double det = 0.0;
  Vector ddet;
  auto det_terms = [&]() {
    if (!have_det) {
      det = det_small(J * J.transpose());
      ddet = model.det_gradient(q, ts);
      have_det = true;
    }
  };
  for (size_t c = 0; c < s.criteria.size(); ++c) {
    const CriterionKind kind = kinds[c];
    Vector g;
    if (kind == CriterionKind::paper || kind == CriterionKind::half_det) {
      det_terms();
      g = 0.5 * ddet;
      if (kind == CriterionKind::paper) g += -s.smoothness.dot(q) * s.smoothness;
    } else if (kind == CriterionKind::manipulability) {
      det_terms();
      g = det <= 1e-300 ? Vector(Vector::Zero(n)) : Vector(ddet / (2.0 * std::sqrt(det)));
    } else if (kind == CriterionKind::joint_limits) {
      Vector b, db;
      barrier(q, b, db);
      g = -db / static_cast<double>(n);
    } else if (kind == CriterionKind::joint_smoothness) {
      g = -s.smoothing_coefficients.dot(q) * s.smoothing_coefficients;
    } else if (kind == CriterionKind::obstacles) {  // sum over pairs of depth * (-n^T ((1 - t) J_a + t J_b))
      Matrix points;
      std::vector<Matrix> jacobians;
      model.chain(q, points, jacobians);
      g = Vector::Zero(n);
      for (const ObstaclePair &p : obstacle_pairs(s, points))
        if (p.depth > 0.0)
          g += -(p.depth * (1 - p.t)) * (jacobians[p.segment].transpose() * p.normal) -
               (p.depth * p.t) * (jacobians[p.segment + 1].transpose() * p.normal);
    } else {  // joint_centering: -(q - c) / (n (u - l)^2)
      g = -centered(q).cwiseQuotient(s.limit_upper - s.limit_lower) / static_cast<double>(n);
    }
    grad += s.criterion_weights[c] * g;
  }
  return grad;
}

// WeightedCriteria.value
double Criteria::value(const Vector &q, const Matrix &J, const Matrix &points) const {
  const int n = static_cast<int>(q.size());
  const double det = det_small(J * J.transpose());
  double h = 0.0;
  for (size_t c = 0; c < s.criteria.size(); ++c) {
    const CriterionKind kind = kinds[c];
    double v;
    if (kind == CriterionKind::paper) {
      const double cq = s.smoothness.dot(q);
      v = 0.5 * det + (-0.5 * cq * cq);
    } else if (kind == CriterionKind::half_det) {
      v = 0.5 * det;
    } else if (kind == CriterionKind::manipulability) {
      v = std::sqrt(std::max(det, 0.0));
    } else if (kind == CriterionKind::joint_limits) {
      Vector b, db;
      barrier(q, b, db);
      v = -b.mean();
    } else if (kind == CriterionKind::joint_smoothness) {
      const double cq = s.smoothing_coefficients.dot(q);
      v = -0.5 * cq * cq;
    } else if (kind == CriterionKind::obstacles) {
      v = 0.0;
      for (const ObstaclePair &p : obstacle_pairs(s, points)) v += p.depth * p.depth;
      v *= -0.5;
    } else {  // joint_centering: -(1/(2n)) sum ((q - c) / (u - l))^2
      v = -0.5 * centered(q).squaredNorm() / static_cast<double>(n);
    }
    h += s.criterion_weights[c] * v;
  }
  return h;
}

}  // namespace nnrobust
