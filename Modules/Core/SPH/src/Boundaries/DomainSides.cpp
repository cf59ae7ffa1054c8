#include "cementsph/sph/Boundaries/DomainSides.h"

#include "cementsph/sph/Simulation.h"

#include <vector>

namespace cementsph::sph {

std::size_t DomainSides::apply(Simulation& sim) {
  FluidParticles& f = sim.fluid();
  const Domain& domain = sim.domain();
  const std::size_t n = f.size();
  std::vector<std::uint8_t> keep;
  std::size_t leaving = 0;
  double* pos[3] = {f.x.data(), f.y.data(), f.z.data()};
  double* prev[3] = {f.xp.data(), f.yp.data(), f.zp.data()};
  const Eigen::Vector3d extent = domain.extent();
  for (int a = 0; a < 3; ++a) {
    const double lo = domain.lower[a], hi = domain.upper[a], L = extent[a];
    if (domain.periodic[a]) {
      for (std::size_t i = 0; i < n; ++i) {
        if (pos[a][i] >= hi) { pos[a][i] -= L; prev[a][i] -= L; }
        else if (pos[a][i] < lo) { pos[a][i] += L; prev[a][i] += L; }
      }
    } else {
      for (std::size_t i = 0; i < n; ++i)
        if (pos[a][i] < lo || pos[a][i] >= hi) {
          if (keep.empty()) keep.assign(n, 1);
          if (keep[i]) { keep[i] = 0; ++leaving; }
        }
    }
  }
  if (leaving) f.compact(keep);
  return leaving;
}

} // namespace cementsph::sph
