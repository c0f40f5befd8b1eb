// The desired motion on the C++ side, the twins of nnrobust/trajectories/: each position path is a
// class in the file named like its Python module, registered under its Python class's `twin` name
// and built from the fields its `twin_fields` list; a pose task adds PoseTrajectory's orientation.
#pragma once

#include <memory>

#include "../fields.hpp"
#include "../registry.hpp"

namespace nnrobust {

// A position path p_d(t) with p_d' and p_d'' (PositionPath.__call__)
struct Path {
  virtual ~Path() = default;
  virtual void at(double t, Vector &p, Vector &dp, Vector &ddp) const = 0;
};

using PathRegistry = Registry<Path, const Fields &>;

// PoseTrajectory's orientation (nnrobust/trajectories/pose.py): R_d(t) = exp3(theta(t) u) R_0,
// theta = A sin(w t + phi); its angular velocity and acceleration are theta' u and theta'' u.
struct Orientation {
  Eigen::Matrix3d rotation0;
  Eigen::Vector3d axis;
  double amplitude, omega, phase;

  explicit Orientation(const Fields &f);
  void at(double t, Eigen::Matrix3d &R, Eigen::Vector3d &w, Eigen::Vector3d &dw) const;
};

}  // namespace nnrobust

// Registers `Class` (constructed as Class(const Fields &)) under `name`.
#define NNROBUST_PATH(name, Class)                                                                     \
  static const bool nnrobust_registered_##Class = ::nnrobust::PathRegistry::add(                      \
      name, [](const ::nnrobust::Fields &f) -> std::unique_ptr<::nnrobust::Path> {                     \
        return std::make_unique<Class>(f);                                                             \
      })

// a twin compiled apart hands its paths over (registry.hpp)
NNROBUST_SHARE_REGISTRY(::nnrobust::PathRegistry, nnrobust_twin_paths)
