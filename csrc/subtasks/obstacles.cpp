// Twin of nnrobust/subtasks/obstacles.py: SphereObstacles.
#include <algorithm>
#include <cmath>

#include "criterion.hpp"

namespace nnrobust {
namespace {

// h = -0.5 sum over (link segment, sphere) of max(0, influence - clearance)^2 (fields: centers
// K x 3, radii, influence, link_radius)
struct SphereObstacles : Criterion {
  Matrix centers;
  Vector radii;
  double influence, link_radius;
  explicit SphereObstacles(const Fields &f)
      : centers(f.matrix("centers")), radii(f.vector("radii")), influence(f.scalar("influence")),
        link_radius(f.scalar("link_radius")) {}

  // SphereObstacles._pairs for every (segment, obstacle): t, the unit normal and the depth
  struct Pair {
    int segment;
    double t, depth;
    Eigen::Vector3d normal;
  };
  std::vector<Pair> pairs(const Matrix &points) const {
    std::vector<Pair> out;
    for (int seg = 0; seg + 1 < points.rows(); ++seg) {
      const Eigen::Vector3d a = points.row(seg).transpose(), b = points.row(seg + 1).transpose(), ab = b - a;
      const double length2 = std::max(ab.squaredNorm(), 1e-300);
      for (int o = 0; o < centers.rows(); ++o) {
        const Eigen::Vector3d c = centers.row(o).transpose();
        const double t = std::clamp((c - a).dot(ab) / length2, 0.0, 1.0);
        const Eigen::Vector3d gap = c - (a + t * ab);
        const double dist = std::max(gap.norm(), 1e-12);
        const double d = dist - radii[o] - link_radius;
        out.push_back({seg, t, std::max(0.0, influence - d), gap / dist});
      }
    }
    return out;
  }
  double value(const Vector &, double, const Matrix &points) const override {
    double v = 0.0;
    for (const Pair &p : pairs(points)) v += p.depth * p.depth;
    return -0.5 * v;
  }
  // sum over pairs of depth * (-n^T ((1 - t) J_a + t J_b)), on the nominal model's chain
  Vector gradient(const Vector &q, DetAtQ &d) const override {
    Matrix points;
    std::vector<Matrix> jacobians;
    d.chain(points, jacobians);
    Vector g = Vector::Zero(q.size());
    for (const Pair &p : pairs(points))
      if (p.depth > 0.0)
        g += -(p.depth * (1 - p.t)) * (jacobians[p.segment].transpose() * p.normal) -
             (p.depth * p.t) * (jacobians[p.segment + 1].transpose() * p.normal);
    return g;
  }
};

}  // namespace
NNROBUST_CRITERION("obstacles", SphereObstacles);
}  // namespace nnrobust
