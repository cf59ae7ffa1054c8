#include "cementsph/sph/DarcyBenchmark.h"

#include "cementsph/sph/Simulation.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>
#include <random>
#include <sstream>

namespace cementsph::sph {

double kozenyCarmanDimensionless(double porosity) {
  const double s = 1.0 - porosity;
  return porosity * porosity * porosity / (180.0 * s * s);
}

std::vector<double> bodyForceSweep(const ModelParameters& model, double spacing) {
  const double reference = 2e-3 * model.soundSpeed * model.soundSpeed / spacing;
  return {reference, 0.8 * reference, 0.6 * reference, 0.4 * reference};
}

ModelParameters darcyModel(const ModelParameters& base, double hOverD, double spacing, double viscosity) {
  ModelParameters m = base;
  m.smoothingLength = hOverD * spacing;
  m.viscosity = viscosity;
  return m;
}

namespace {

// Fisher-Yates with std::mt19937_64, written out so the fixed sites are the same on every platform
// (std::shuffle's algorithm is implementation-defined).
std::vector<std::uint8_t> chooseFixedSites(std::size_t sites, std::size_t fixedCount, std::uint64_t seed) {
  std::vector<std::uint32_t> index(sites);
  std::iota(index.begin(), index.end(), 0u);
  std::mt19937_64 rng(seed);
  for (std::size_t i = sites - 1; i > 0; --i) {
    const std::size_t j = static_cast<std::size_t>(rng() % (i + 1));
    std::swap(index[i], index[j]);
  }
  std::vector<std::uint8_t> fixed(sites, 0);
  for (std::size_t k = 0; k < fixedCount; ++k) fixed[index[k]] = 1;
  return fixed;
}

} // namespace

DarcyResult DarcyBenchmark::run(const DarcyCase& c, const Progress& progress) const {
  const auto start = std::chrono::steady_clock::now();
  DarcyResult result;
  result.input = c;
  const ModelParameters model = darcyModel(base_, hOverD_, c.spacing, c.viscosity);
  const std::vector<double> forces = c.bodyForces.empty() ? bodyForceSweep(model, c.spacing) : c.bodyForces;
  if (forces.size() < 2) throw SimulationError("the Darcy fit needs at least two body forces");
  for (double f : forces)
    if (!(std::isfinite(f) && f > 0)) throw SimulationError("body forces must be positive");

  // --- the medium ---------------------------------------------------------------------------------
  if (c.latticeSize < 4) throw SimulationError("Darcy lattice must have at least 4 particles per side");
  if (!(c.spacing > 0)) throw SimulationError("Darcy particle spacing must be positive");
  if (!(c.porosity > 0.0 && c.porosity <= 1.0))
    throw SimulationError("porosity " + std::to_string(c.porosity) +
                          " is outside (0, 1]: porosity 0 leaves no fluid to flow");
  const std::size_t n = static_cast<std::size_t>(c.latticeSize);
  const std::size_t sites = n * n * n;
  const auto fixedCount = static_cast<std::size_t>(std::llround((1.0 - c.porosity) * static_cast<double>(sites)));
  if (fixedCount >= sites) throw SimulationError("porosity too low: no fluid particle left in the lattice");
  result.porosity = 1.0 - double(fixedCount) / double(sites);

  Domain domain;
  domain.lower.setZero();
  domain.upper.setConstant(static_cast<double>(n) * c.spacing);
  domain.periodic = {true, true, true};
  Simulation sim(model, domain);
  const double mass = model.restDensity * c.spacing * c.spacing * c.spacing; // particles occupy d^3
  const std::vector<std::uint8_t> fixed = chooseFixedSites(sites, fixedCount, c.seed);
  sim.reserveFluid(sites - fixedCount);
  for (std::size_t k = 0; k < n; ++k)
    for (std::size_t j = 0; j < n; ++j)
      for (std::size_t i = 0; i < n; ++i) {
        const Eigen::Vector3d p = (Eigen::Vector3d(double(i), double(j), double(k)).array() + 0.5).matrix() * c.spacing;
        if (fixed[i + n * (j + n * k)]) sim.addFixedParticle(p, mass);
        else sim.addFluidParticle(p, Eigen::Vector3d::Zero(), mass);
      }

  // Mid-plane: fluid particles within h of x = L/2 (the paper averages over the mid-section plane);
  // the travel is that of all fluid particles.
  const double mid = 0.5 * domain.upper.x(), halfSlab = model.smoothingLength;
  auto velocities = [&](double& midPlane, double& all) {
    const FluidParticles& f = sim.fluid();
    double sum = 0, sumAll = 0;
    std::size_t count = 0;
    for (std::size_t i = 0; i < f.size(); ++i) {
      sumAll += f.vx[i];
      if (std::abs(f.x[i] - mid) < halfSlab) { sum += f.vx[i]; ++count; }
    }
    midPlane = count ? sum / double(count) : 0.0;
    all = sumAll / double(f.size());
  };

  // Fewest steps a spacing of travel can take: free drag-limited flow (u = F / gamma) is the fastest,
  // and the densest particle has the weakest drag.
  {
    sim.updateDensityAndPressure();
    const std::vector<double>& rho = sim.fluid().density;
    const double densest = *std::max_element(rho.begin(), rho.end());
    const double weakestDrag = model.viscosityModel == ViscosityModel::Drag ? model.dragRate(mass, densest) : 0.0;
    sim.updateAccelerations();
    const double dt = sim.nextTimeStep();
    const double fMin = *std::min_element(forces.begin(), forces.end());
    if (weakestDrag > 0 && dt > 0 && progress) {
      const double stepsPerSpacing = c.spacing * weakestDrag / (fMin * dt);
      if (stepsPerSpacing * 2.0 * criteria_.windowTravel > double(criteria_.maxSteps)) {
        std::ostringstream s;
        s << "warning: the " << toString(model.integrator) << " integrator needs at least " << std::llround(stepsPerSpacing)
          << " steps per spacing travelled here (dt " << dt << " s), more than the step cap allows: this case will "
          << "stop unconverged; the overdamped integrator takes the same physics in far fewer steps";
        progress(s.str());
      }
    }
  }
  result.converged = true;
  const double freeDrag = model.viscosityModel == ViscosityModel::Drag ? model.dragRate(mass, model.restDensity) : 0.0;
  for (double force : forces) {
    sim.setBodyForce(Eigen::Vector3d(force, 0, 0));
    DarcyPoint p;
    p.bodyForce = force;
    const std::uint64_t firstStep = sim.statistics().steps;
    const double firstTime = sim.time();
    // A window also closes after the time free drag-limited flow (u = F / gamma) needs to travel 50
    // spacings: a medium that does not percolate jams (u -> 0), which is a steady state too (k = 0).
    // Agreement is then judged against a floor of 1e-3 of the free-flow velocity.
    const double freeVelocity = freeDrag > 0 ? force / freeDrag : 0.0;
    const double maxWindowTime = freeVelocity > 0 ? 50.0 * c.spacing / freeVelocity
                                                  : std::numeric_limits<double>::infinity();
    const double velocityFloor = 1e-3 * freeVelocity;
    double previousMean = std::numeric_limits<double>::quiet_NaN();
    int agreeing = 0;
    while (sim.statistics().steps - firstStep < criteria_.maxSteps) {
      double sum = 0, time = 0, travel = 0;
      while (travel < criteria_.windowTravel * c.spacing && time < maxWindowTime &&
             sim.statistics().steps - firstStep < criteria_.maxSteps) {
        const double dt = sim.step();
        double uMid, uAll;
        velocities(uMid, uAll);
        sum += uMid * dt;
        time += dt;
        travel += std::abs(uAll) * dt;
      }
      const double mean = sum / time;
      const double scale = std::max(std::abs(mean), velocityFloor);
      if (std::isfinite(previousMean) && std::abs(mean - previousMean) <= criteria_.relativeTolerance * scale)
        ++agreeing;
      else
        agreeing = 0;
      previousMean = mean;
      p.meanVelocity = mean;
      if (agreeing >= criteria_.agreeingWindows) {
        p.converged = true;
        break;
      }
    }
    p.steps = sim.statistics().steps - firstStep;
    p.simulatedTime = sim.time() - firstTime;
    result.steps += p.steps;
    result.converged = result.converged && p.converged;
    result.points.push_back(p);
    if (progress) {
      std::ostringstream s;
      s.precision(3);
      s << "porosity " << c.porosity << ", d " << c.spacing * 1e3 << " mm, mu " << c.viscosity << " Pa.s: F_B "
        << force << " m/s^2 -> u " << p.meanVelocity << " m/s in " << p.steps << " steps"
        << (p.converged ? "" : " (NOT converged)");
      progress(s.str());
    }
  }
  // u_bar / F_B: slope of the least-squares line. Darcy's law passes through the origin, so the slope
  // is fitted through it; R^2 is of the free line (it tests linearity without forcing the origin).
  const std::size_t m = result.points.size();
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (const DarcyPoint& p : result.points) {
    sx += p.bodyForce; sy += p.meanVelocity; sxx += p.bodyForce * p.bodyForce;
    sxy += p.bodyForce * p.meanVelocity;
  }
  result.slope = sxy / sxx;
  const double mm = double(m);
  const double freeSlope = (mm * sxy - sx * sy) / (mm * sxx - sx * sx);
  result.intercept = (sy - freeSlope * sx) / mm;
  double ssRes = 0, ssTot = 0;
  for (const DarcyPoint& p : result.points) {
    const double fit = result.intercept + freeSlope * p.bodyForce;
    ssRes += (p.meanVelocity - fit) * (p.meanVelocity - fit);
    ssTot += (p.meanVelocity - sy / mm) * (p.meanVelocity - sy / mm);
  }
  result.r2 = ssTot > 0 ? 1.0 - ssRes / ssTot : 1.0;
  // Eq. 12: k = mu eps u_bar / (rho0 F_B).
  result.permeability = c.viscosity * result.porosity * result.slope / model.restDensity;
  result.dimensionlessPermeability = result.permeability / (c.spacing * c.spacing);
  result.wallSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

} // namespace cementsph::sph
