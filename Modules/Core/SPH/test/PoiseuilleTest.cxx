// Poiseuille start-up between plates at y = 0 and y = L with Morris viscosity (Eq. 7) and the
// explicit integrator, against the series of Morris, Fox & Zhu 1997 (model-notes 4):
//   v(y,t) = F/(2 nu) y (L - y) - sum_n 4 F L^2 / (nu pi^3 (2n+1)^3) sin((2n+1) pi y / L) exp(-(2n+1)^2 pi^2 nu t / L^2)
// Walls are three layers of fixed particles (zero velocity: the no-slip condition through Eq. 7).
// With zero-velocity fixed particles (the paper's solid; no extrapolated wall velocities as in Morris
// et al.), the no-slip plane lies on the first layer of fixed particles, not half a spacing inside it
// (measured: a 16 % faster centreline with plates put midway). So the plates of the oracle stand on
// the first wall layers: L = (fluid layers + 1) d. In a CT scene the same holds: the solid surface is at
// the centres of the outermost solid voxels.
#include "cementsph/sph/Simulation.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace cementsph::sph;

namespace {

double poiseuilleStartUp(double y, double t, double F, double nu, double L) {
  double v = F / (2 * nu) * y * (L - y);
  for (int n = 0; n < 200; ++n) {
    const double k = 2 * n + 1;
    v -= 4 * F * L * L / (nu * kPi * kPi * kPi * k * k * k) * std::sin(k * kPi * y / L) *
         std::exp(-k * k * kPi * kPi * nu * t / (L * L));
  }
  return v;
}

} // namespace

TEST(SPHPoiseuille, MorrisStartUpMatchesSeries) {
  const double d = 1e-4;      // spacing [m]
  const int nFluid = 12;      // fluid layers across the channel
  const int nWall = 3, nPeriodic = 6;
  const double L = (nFluid + 1) * d; // plates on the first fixed layers, y = -d/2 and (nFluid + 1/2) d
  ModelParameters m;
  m.restDensity = 1000.0;
  m.smoothingLength = 1.0 * d;
  m.viscosity = 1.0;                                   // nu = 1e-3 m^2/s
  m.viscosityModel = ViscosityModel::Morris;
  m.integrator = Integrator::Explicit;
  const double nu = m.viscosity / m.restDensity;
  const double vmax = 1e-3;                            // keep Mach = vmax / cs = 0.01
  const double F = 8 * nu * vmax / (L * L);
  m.soundSpeed = vmax / 0.01;
  m.bodyForce = Eigen::Vector3d(F, 0, 0);
  Domain domain;
  domain.lower = Eigen::Vector3d(0, -(nWall + 1) * d, 0);
  domain.upper = Eigen::Vector3d(nPeriodic * d, (nFluid + nWall + 1) * d, nPeriodic * d);
  domain.periodic = {true, false, true};
  Simulation sim(m, domain);
  const double mass = m.restDensity * d * d * d;
  for (int k = 0; k < nPeriodic; ++k)
    for (int j = -nWall; j < nFluid + nWall; ++j)
      for (int i = 0; i < nPeriodic; ++i) {
        const Eigen::Vector3d p((i + 0.5) * d, (j + 0.5) * d, (k + 0.5) * d);
        if (j < 0 || j >= nFluid) sim.addFixedParticle(p, mass);
        else sim.addFluidParticle(p, Eigen::Vector3d::Zero(), mass);
      }

  const double tViscous = L * L / nu;
  for (double fraction : {0.02, 0.05, 0.1, 0.2, 1.0}) {
    const double target = fraction * tViscous;
    while (sim.time() < target) sim.step();
    double err2 = 0, ref2 = 0;
    const FluidParticles& f = sim.fluid();
    for (std::size_t i = 0; i < f.size(); ++i) {
      const double exact = poiseuilleStartUp(f.y[i] + 0.5 * d, sim.time(), F, nu, L);
      err2 += (f.vx[i] - exact) * (f.vx[i] - exact);
      ref2 += exact * exact;
    }
    const double relL2 = std::sqrt(err2 / ref2);
    std::cout << "t = " << fraction << " L^2/nu: relative L2 error " << relL2 << "\n";
    EXPECT_LE(relL2, 0.02) << "t = " << fraction << " L^2/nu"; // issue: <= 2 %
  }
}
