// PoseTrajectory's orientation (nnrobust/trajectories/pose.py).
#include <cmath>

#include <pinocchio/spatial/explog.hpp>

#include "trajectory.hpp"

namespace nnrobust {

Orientation::Orientation(const Fields &f)
    : rotation0(f.matrix("rotation0")), axis(f.vector("axis")), amplitude(f.scalar("amplitude")),
      omega(f.scalar("omega")), phase(f.scalar("phase")) {}

void Orientation::at(double t, Eigen::Matrix3d &R, Eigen::Vector3d &w, Eigen::Vector3d &dw) const {
  const double arg = omega * t + phase;
  const double theta = amplitude * std::sin(arg);
  R = pinocchio::exp3(Eigen::Vector3d(theta * axis)) * rotation0;
  w = amplitude * omega * std::cos(arg) * axis;
  dw = -amplitude * omega * omega * std::sin(arg) * axis;
}

}  // namespace nnrobust
