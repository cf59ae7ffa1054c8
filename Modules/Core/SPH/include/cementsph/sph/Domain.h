// The simulation box. Each axis is periodic (the Darcy box: a particle leaving one side re-enters the
// opposite one with its velocity and density) or open (a particle leaving the box is removed and counted).
#pragma once

#include <Eigen/Core>

#include <array>

namespace cementsph::sph {

struct Domain {
  Eigen::Vector3d lower = Eigen::Vector3d::Zero();
  Eigen::Vector3d upper = Eigen::Vector3d::Ones();
  std::array<bool, 3> periodic{false, false, false};

  Eigen::Vector3d extent() const { return upper - lower; }
  bool contains(const Eigen::Vector3d& p) const {
    return (p.array() >= lower.array()).all() && (p.array() < upper.array()).all();
  }
};

} // namespace cementsph::sph
