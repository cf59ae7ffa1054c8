#include "cementsph/sph/Simulation.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

namespace cementsph::sph {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();

std::string formatSeconds(double s) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3g s", s);
  return b;
}
} // namespace

double StepLimits::stable() const { return std::min({acoustic, viscous, drag, force, overdamped}); }

Simulation::Simulation(const ModelParameters& parameters, const Domain& domain)
    : parameters_(parameters), domain_(domain), densityKernel_(parameters.smoothingLength),
      pressureKernel_(parameters.smoothingLength) {
  validateParameters();
  const double listRadius = densityKernel_.support() * (1.0 + 0.5 * parameters_.neighbourSkin);
  grid_.configure(domain_, listRadius);
  const Eigen::Vector3d e = domain_.extent();
  for (int a = 0; a < 3; ++a) {
    anyPeriodic_ = anyPeriodic_ || domain_.periodic[a];
    extent_[a] = e[a];
    halfExtent_[a] = domain_.periodic[a] ? 0.5 * e[a] : kInf;
  }
  fixed_.density = parameters_.restDensity;
  fixed_.pressure = parameters_.pressure(fixed_.density);
}

void Simulation::validateParameters() const {
  const ModelParameters& p = parameters_;
  auto require = [](bool ok, const std::string& what) {
    if (!ok) throw SimulationError(what);
  };
  require(std::isfinite(p.restDensity) && p.restDensity > 0, "rest density must be positive");
  require(std::isfinite(p.soundSpeed) && p.soundSpeed > 0, "speed of sound must be positive");
  require(std::isfinite(p.smoothingLength) && p.smoothingLength > 0, "smoothing length h must be positive");
  require(std::isfinite(p.viscosity) && p.viscosity >= 0, "viscosity must be zero or positive");
  require(p.neighbourSkin >= 0 && p.neighbourSkin <= 2, "neighbour skin must be within 0..2 h");
  if (p.viscosityModel != ViscosityModel::None)
    require(p.viscosity > 0, "viscosity must be positive for the " + toString(p.viscosityModel) + " model");
  if (p.viscosityModel == ViscosityModel::Drag)
    require(std::isfinite(p.dragCoefficient) && p.dragCoefficient > 0, "drag coefficient Cf must be positive");
  if (p.integrator == Integrator::Overdamped)
    require(p.viscosityModel == ViscosityModel::Drag,
            "the overdamped integrator is the creeping-flow limit of the drag model (Eq. 9): use --viscosity-model drag");
  if (p.integrator == Integrator::CentralDifference)
    require(p.viscosityModel != ViscosityModel::Morris,
            "the central-difference integrator (Eq. 8) is implicit in the drag only; Morris viscosity (Eq. 7) "
            "needs the explicit integrator");
  if (p.fixedTimeStep) require(std::isfinite(*p.fixedTimeStep) && *p.fixedTimeStep > 0, "time step must be positive");
  if (p.maxTimeStep) require(std::isfinite(*p.maxTimeStep) && *p.maxTimeStep > 0, "maximum time step must be positive");
  const double listRadius = 2.0 * p.smoothingLength * (1.0 + 0.5 * p.neighbourSkin);
  const Eigen::Vector3d e = domain_.extent();
  for (int a = 0; a < 3; ++a) {
    require(e[a] > 0, "simulation domain has zero or negative extent");
    if (domain_.periodic[a])
      require(e[a] > 2.0 * listRadius, "periodic box is narrower than twice the neighbour radius (" +
                                            std::to_string(listRadius * 1e3) + " mm)");
  }
}

void Simulation::setViscosity(double viscosityPaS) {
  if (!(std::isfinite(viscosityPaS) && viscosityPaS > 0)) throw SimulationError("viscosity must be positive");
  parameters_.viscosity = viscosityPaS;
}

std::uint64_t Simulation::addFluidParticle(const Eigen::Vector3d& position, const Eigen::Vector3d& velocity,
                                           double mass) {
  if (!position.allFinite() || !velocity.allFinite() || !(mass > 0))
    throw SimulationError("fluid particle with a non-finite position or velocity, or non-positive mass");
  if (!domain_.contains(position)) throw SimulationError("fluid particle placed outside the domain");
  const std::size_t i = fluid_.add(position, velocity, mass, parameters_.restDensity, time_, nextId_);
  if (centralDifferenceStep_ > 0) { // Eq. 8 needs a previous position: one consistent with v
    fluid_.xp[i] = position.x() - velocity.x() * centralDifferenceStep_;
    fluid_.yp[i] = position.y() - velocity.y() * centralDifferenceStep_;
    fluid_.zp[i] = position.z() - velocity.z() * centralDifferenceStep_;
  }
  listsValid_ = false;
  return nextId_++;
}

void Simulation::addFixedParticle(const Eigen::Vector3d& position, double mass) {
  if (!position.allFinite() || !(mass > 0)) throw SimulationError("fixed particle with a non-finite position or non-positive mass");
  if (!domain_.contains(position)) throw SimulationError("fixed particle placed outside the domain");
  fixed_.add(position, mass);
  fixedBinned_ = false;
  listsValid_ = false;
}

std::size_t Simulation::bytesPerFixedParticle() const {
  if (fixed_.size() == 0) return 0;
  // Positions and masses, plus the share of the fixed grid's cell offsets.
  const std::size_t bytes = fixed_.bytesUsed() + fixedCellStart_.capacity() * sizeof(std::uint32_t);
  return bytes / fixed_.size();
}

// ------------------------------------------------------------------------------------------------
// Neighbour lists
// ------------------------------------------------------------------------------------------------

bool Simulation::listsNeedRebuild() const {
  if (!listsValid_ || !fixedBinned_ || refX_.size() != fluid_.size()) return true;
  const double skin = parameters_.neighbourSkin * parameters_.smoothingLength;
  if (skin <= 0) return true;
  const double limit2 = 0.25 * skin * skin; // rebuild once any particle moved half the skin
  const std::size_t n = fluid_.size();
  int exceeded = 0;
#pragma omp parallel for schedule(static) reduction(max : exceeded)
  for (std::size_t i = 0; i < n; ++i) {
    double d[3] = {fluid_.x[i] - refX_[i], fluid_.y[i] - refY_[i], fluid_.z[i] - refZ_[i]};
    if (anyPeriodic_)
      for (int a = 0; a < 3; ++a) {
        if (d[a] > halfExtent_[a]) d[a] -= extent_[a];
        else if (d[a] < -halfExtent_[a]) d[a] += extent_[a];
      }
    if (d[0] * d[0] + d[1] * d[1] + d[2] * d[2] > limit2) exceeded = 1;
  }
  return exceeded != 0;
}

void Simulation::rebuildNeighbourLists() {
  std::vector<std::uint32_t> order;
  if (!fixedBinned_) {
    // Fixed particles are static: bin once and store them cell by cell.
    grid_.bin(fixed_.x.data(), fixed_.y.data(), fixed_.z.data(), fixed_.size(), order, fixedCellStart_);
    std::vector<double> s(order.size());
    for (auto* f : {&fixed_.x, &fixed_.y, &fixed_.z}) {
      for (std::size_t k = 0; k < order.size(); ++k) s[k] = (*f)[order[k]];
      f->swap(s);
      s.resize(order.size());
    }
    std::vector<float> sm(order.size());
    for (std::size_t k = 0; k < order.size(); ++k) sm[k] = fixed_.mass[order[k]];
    fixed_.mass.swap(sm);
    fixed_.x.shrink_to_fit(); fixed_.y.shrink_to_fit(); fixed_.z.shrink_to_fit(); fixed_.mass.shrink_to_fit();
    fixedBinned_ = true;
  }
  // Fluid particles are reordered by cell so that neighbours are close in memory.
  grid_.bin(fluid_.x.data(), fluid_.y.data(), fluid_.z.data(), fluid_.size(), order, fluidCellStart_);
  fluid_.permute(order);
  if (anyPeriodic_) buildLists<true>();
  else buildLists<false>();
  refX_ = fluid_.x;
  refY_ = fluid_.y;
  refZ_ = fluid_.z;
  listsValid_ = true;
  ++statistics_.neighbourRebuilds;
}

template <bool Periodic> void Simulation::buildLists() {
  const std::size_t n = fluid_.size();
  const double radius = densityKernel_.support() + parameters_.neighbourSkin * parameters_.smoothingLength;
  const double r2max = radius * radius;
  const double* X = fluid_.x.data(); const double* Y = fluid_.y.data(); const double* Z = fluid_.z.data();
  const double* FX = fixed_.x.data(); const double* FY = fixed_.y.data(); const double* FZ = fixed_.z.data();

  auto within = [&](double xi, double yi, double zi, double xj, double yj, double zj) {
    double dx = xi - xj, dy = yi - yj, dz = zi - zj;
    if constexpr (Periodic) {
      if (dx > halfExtent_[0]) dx -= extent_[0]; else if (dx < -halfExtent_[0]) dx += extent_[0];
      if (dy > halfExtent_[1]) dy -= extent_[1]; else if (dy < -halfExtent_[1]) dy += extent_[1];
      if (dz > halfExtent_[2]) dz -= extent_[2]; else if (dz < -halfExtent_[2]) dz += extent_[2];
    }
    return dx * dx + dy * dy + dz * dz < r2max;
  };
  // Two passes (count, then fill) make the lists in parallel without locks, and deterministic.
  auto visit = [&](std::size_t i, auto&& onFluid, auto&& onFixed) {
    const int cell = grid_.cellOf(X[i], Y[i], Z[i]);
    for (const std::uint32_t* c = grid_.neighbourCellsBegin(cell); c != grid_.neighbourCellsEnd(cell); ++c) {
      for (std::uint32_t j = fluidCellStart_[*c]; j < fluidCellStart_[*c + 1]; ++j)
        if (j != i && within(X[i], Y[i], Z[i], X[j], Y[j], Z[j])) onFluid(j);
      if (!fixedCellStart_.empty())
        for (std::uint32_t j = fixedCellStart_[*c]; j < fixedCellStart_[*c + 1]; ++j)
          if (within(X[i], Y[i], Z[i], FX[j], FY[j], FZ[j])) onFixed(j);
    }
  };
  fluidNeighbours_.offset.assign(n + 1, 0);
  fixedNeighbours_.offset.assign(n + 1, 0);
#pragma omp parallel for schedule(static)
  for (std::size_t i = 0; i < n; ++i) {
    std::uint64_t nf = 0, ns = 0;
    visit(i, [&](std::uint32_t) { ++nf; }, [&](std::uint32_t) { ++ns; });
    fluidNeighbours_.offset[i + 1] = nf;
    fixedNeighbours_.offset[i + 1] = ns;
  }
  for (std::size_t i = 0; i < n; ++i) {
    fluidNeighbours_.offset[i + 1] += fluidNeighbours_.offset[i];
    fixedNeighbours_.offset[i + 1] += fixedNeighbours_.offset[i];
  }
  fluidNeighbours_.index.resize(fluidNeighbours_.offset[n]);
  fixedNeighbours_.index.resize(fixedNeighbours_.offset[n]);
#pragma omp parallel for schedule(static)
  for (std::size_t i = 0; i < n; ++i) {
    std::uint64_t pf = fluidNeighbours_.offset[i], ps = fixedNeighbours_.offset[i];
    visit(i, [&](std::uint32_t j) { fluidNeighbours_.index[pf++] = j; },
          [&](std::uint32_t j) { fixedNeighbours_.index[ps++] = j; });
  }
}

// ------------------------------------------------------------------------------------------------
// Density (Eq. 2) and pressure (Eq. 6)
// ------------------------------------------------------------------------------------------------

void Simulation::updateDensityAndPressure() {
  if (listsNeedRebuild()) rebuildNeighbourLists();
  if (anyPeriodic_) densityPass<true>();
  else densityPass<false>();
}

#define CEMENTSPH_MINIMUM_IMAGE(dx, dy, dz)                                                           \
  if constexpr (Periodic) {                                                                           \
    if (dx > halfExtent_[0]) dx -= extent_[0]; else if (dx < -halfExtent_[0]) dx += extent_[0];       \
    if (dy > halfExtent_[1]) dy -= extent_[1]; else if (dy < -halfExtent_[1]) dy += extent_[1];       \
    if (dz > halfExtent_[2]) dz -= extent_[2]; else if (dz < -halfExtent_[2]) dz += extent_[2];       \
  }

template <bool Periodic> void Simulation::densityPass() {
  const std::size_t n = fluid_.size();
  const double support2 = densityKernel_.support() * densityKernel_.support();
  const double w0 = densityKernel_.value(0.0);
  const double cs2 = parameters_.soundSpeed * parameters_.soundSpeed, rho0 = parameters_.restDensity;
  const double* X = fluid_.x.data(); const double* Y = fluid_.y.data(); const double* Z = fluid_.z.data();
  const double* M = fluid_.mass.data();
  const double* FX = fixed_.x.data(); const double* FY = fixed_.y.data(); const double* FZ = fixed_.z.data();
  const float* FM = fixed_.mass.data();
  const std::uint32_t* fl = fluidNeighbours_.index.data();
  const std::uint32_t* sl = fixedNeighbours_.index.data();
#pragma omp parallel for schedule(static)
  for (std::size_t i = 0; i < n; ++i) {
    const double xi = X[i], yi = Y[i], zi = Z[i];
    double rho = M[i] * w0; // the particle itself
    for (std::uint64_t k = fluidNeighbours_.offset[i]; k < fluidNeighbours_.offset[i + 1]; ++k) {
      const std::uint32_t j = fl[k];
      double dx = xi - X[j], dy = yi - Y[j], dz = zi - Z[j];
      CEMENTSPH_MINIMUM_IMAGE(dx, dy, dz)
      const double r2 = dx * dx + dy * dy + dz * dz;
      if (r2 < support2) rho += M[j] * densityKernel_.value(std::sqrt(r2));
    }
    for (std::uint64_t k = fixedNeighbours_.offset[i]; k < fixedNeighbours_.offset[i + 1]; ++k) {
      const std::uint32_t j = sl[k];
      double dx = xi - FX[j], dy = yi - FY[j], dz = zi - FZ[j];
      CEMENTSPH_MINIMUM_IMAGE(dx, dy, dz)
      const double r2 = dx * dx + dy * dy + dz * dz;
      if (r2 < support2) rho += static_cast<double>(FM[j]) * densityKernel_.value(std::sqrt(r2));
    }
    fluid_.density[i] = rho;
    fluid_.pressure[i] = cs2 * (rho - rho0);
  }
}

// ------------------------------------------------------------------------------------------------
// Accelerations: pressure (Eq. 5), body force, Morris viscosity (Eq. 7)
// ------------------------------------------------------------------------------------------------

void Simulation::updateAccelerations() {
  const bool morris = parameters_.viscosityModel == ViscosityModel::Morris;
  if (anyPeriodic_) morris ? forcePass<true, true>() : forcePass<true, false>();
  else morris ? forcePass<false, true>() : forcePass<false, false>();
}

template <bool Periodic, bool Morris> void Simulation::forcePass() {
  const std::size_t n = fluid_.size();
  const double h = parameters_.smoothingLength;
  const double support2 = 4.0 * h * h;
  const double eta2 = 0.01 * h * h; // Eq. 7 regularisation (Morris et al. 1997)
  const double twoMu = 2.0 * parameters_.viscosity;
  const Eigen::Vector3d g = parameters_.bodyForce;
  // p / rho^2 of each particle, used by every pair (Eq. 5).
  pressureOverDensity2_.resize(n);
  double* pr2 = pressureOverDensity2_.data();
#pragma omp parallel for schedule(static)
  for (std::size_t i = 0; i < n; ++i) pr2[i] = fluid_.pressure[i] / (fluid_.density[i] * fluid_.density[i]);
  const double fixedPr2 = fixed_.pressure / (fixed_.density * fixed_.density);
  const double* X = fluid_.x.data(); const double* Y = fluid_.y.data(); const double* Z = fluid_.z.data();
  const double* VX = fluid_.vx.data(); const double* VY = fluid_.vy.data(); const double* VZ = fluid_.vz.data();
  const double* M = fluid_.mass.data(); const double* RHO = fluid_.density.data();
  const double* FX = fixed_.x.data(); const double* FY = fixed_.y.data(); const double* FZ = fixed_.z.data();
  const float* FM = fixed_.mass.data();
  const std::uint32_t* fl = fluidNeighbours_.index.data();
  const std::uint32_t* sl = fixedNeighbours_.index.data();
  const double fixedRho = fixed_.density;
#pragma omp parallel for schedule(static)
  for (std::size_t i = 0; i < n; ++i) {
    const double xi = X[i], yi = Y[i], zi = Z[i];
    const double pi = pr2[i];
    double ax = g.x(), ay = g.y(), az = g.z();
    [[maybe_unused]] double vxi = 0, vyi = 0, vzi = 0, rhoi = 0;
    if constexpr (Morris) { vxi = VX[i]; vyi = VY[i]; vzi = VZ[i]; rhoi = RHO[i]; }
    for (std::uint64_t k = fluidNeighbours_.offset[i]; k < fluidNeighbours_.offset[i + 1]; ++k) {
      const std::uint32_t j = fl[k];
      double dx = xi - X[j], dy = yi - Y[j], dz = zi - Z[j];
      CEMENTSPH_MINIMUM_IMAGE(dx, dy, dz)
      const double r2 = dx * dx + dy * dy + dz * dz;
      if (r2 >= support2) continue;
      const double r = std::sqrt(r2);
      double ux, uy, uz;
      if (r > 1e-12 * h) { ux = dx / r; uy = dy / r; uz = dz / r; }
      else { // coincident pair: the spiky gradient is finite, its direction is not; split them
        ux = (i < j) ? 1.0 : -1.0; uy = 0.0; uz = 0.0; // along x, antisymmetric: momentum conserved
      }
      // Eq. 5: a_i -= m_j (p_i/rho_i^2 + p_j/rho_j^2) grad W_spiky
      const double f = -M[j] * (pi + pr2[j]) * pressureKernel_.derivative(r);
      ax += f * ux; ay += f * uy; az += f * uz;
      if constexpr (Morris) {
        // Eq. 7: m_j (mu_i + mu_j) / (rho_i rho_j) (r_ij . grad W) / (r_ij^2 + 0.01 h^2) (v_i - v_j)
        const double v = M[j] * twoMu / (rhoi * RHO[j]) * (r * densityKernel_.derivative(r)) / (r2 + eta2);
        ax += v * (vxi - VX[j]); ay += v * (vyi - VY[j]); az += v * (vzi - VZ[j]);
      }
    }
    for (std::uint64_t k = fixedNeighbours_.offset[i]; k < fixedNeighbours_.offset[i + 1]; ++k) {
      const std::uint32_t j = sl[k];
      double dx = xi - FX[j], dy = yi - FY[j], dz = zi - FZ[j];
      CEMENTSPH_MINIMUM_IMAGE(dx, dy, dz)
      const double r2 = dx * dx + dy * dy + dz * dz;
      if (r2 >= support2) continue;
      const double r = std::sqrt(r2);
      double ux = 1.0, uy = 0.0, uz = 0.0; // a fluid particle exactly on a fixed one is pushed along +x
      if (r > 1e-12 * h) { ux = dx / r; uy = dy / r; uz = dz / r; }
      const double mj = static_cast<double>(FM[j]);
      const double f = -mj * (pi + fixedPr2) * pressureKernel_.derivative(r);
      ax += f * ux; ay += f * uy; az += f * uz;
      if constexpr (Morris) { // fixed particles have zero velocity: the no-slip condition
        const double v = mj * twoMu / (rhoi * fixedRho) * (r * densityKernel_.derivative(r)) / (r2 + eta2);
        ax += v * vxi; ay += v * vyi; az += v * vzi;
      }
    }
    fluid_.ax[i] = ax; fluid_.ay[i] = ay; fluid_.az[i] = az;
  }
}
#undef CEMENTSPH_MINIMUM_IMAGE

// ------------------------------------------------------------------------------------------------
// Time step
// ------------------------------------------------------------------------------------------------

double Simulation::maxDragRate() const {
  if (parameters_.viscosityModel != ViscosityModel::Drag) return 0;
  double g = 0;
  const std::size_t n = fluid_.size();
#pragma omp parallel for schedule(static) reduction(max : g)
  for (std::size_t i = 0; i < n; ++i) g = std::max(g, parameters_.dragRate(fluid_.mass[i], fluid_.density[i]));
  return g;
}

double Simulation::minDragRate() const {
  if (parameters_.viscosityModel != ViscosityModel::Drag) return 0;
  double g = kInf;
  const std::size_t n = fluid_.size();
#pragma omp parallel for schedule(static) reduction(min : g)
  for (std::size_t i = 0; i < n; ++i) g = std::min(g, parameters_.dragRate(fluid_.mass[i], fluid_.density[i]));
  return g;
}

StepLimits Simulation::currentLimits() const {
  const ModelParameters& p = parameters_;
  const double h = p.smoothingLength;
  StepLimits l{kInf, kInf, kInf, kInf, kInf, kInf};
  double amax2 = 0, vmax2 = 0;
  const std::size_t n = fluid_.size();
  if (p.integrator == Integrator::Overdamped) {
    const double gmin = minDragRate();
    l.overdamped = p.overdampedStability * gmin * h * h / (p.soundSpeed * p.soundSpeed);
    // v = a / gamma; the fastest particle bounds the step for accuracy.
#pragma omp parallel for schedule(static) reduction(max : vmax2)
    for (std::size_t i = 0; i < n; ++i) {
      const double g = p.dragRate(fluid_.mass[i], fluid_.density[i]);
      const double a2 = fluid_.ax[i] * fluid_.ax[i] + fluid_.ay[i] * fluid_.ay[i] + fluid_.az[i] * fluid_.az[i];
      vmax2 = std::max(vmax2, a2 / (g * g));
    }
    if (vmax2 > 0) l.displacement = p.maxDisplacement * h / std::sqrt(vmax2);
    return l;
  }
  l.acoustic = p.acousticCourant * h / p.soundSpeed;
#pragma omp parallel for schedule(static) reduction(max : amax2)
  for (std::size_t i = 0; i < n; ++i)
    amax2 = std::max(amax2, fluid_.ax[i] * fluid_.ax[i] + fluid_.ay[i] * fluid_.ay[i] + fluid_.az[i] * fluid_.az[i]);
  if (amax2 > 0) l.force = p.forceCourant * std::sqrt(h / std::sqrt(amax2));
  if (p.integrator == Integrator::Explicit) {
    if (p.viscosityModel == ViscosityModel::Morris) l.viscous = p.viscousNumber * h * h * p.restDensity / p.viscosity;
    if (p.viscosityModel == ViscosityModel::Drag) {
      const double g = maxDragRate();
      if (g > 0) l.drag = 1.0 / g;
    }
  }
  return l;
}

double Simulation::chooseTimeStep(const StepLimits& limits) {
  const ModelParameters& p = parameters_;
  const double stable = limits.stable();
  if (p.integrator == Integrator::CentralDifference && centralDifferenceStep_ > 0) return centralDifferenceStep_;
  double dt;
  if (p.fixedTimeStep) {
    dt = *p.fixedTimeStep;
    if (dt > stable) {
      std::string which = "acoustic";
      if (stable == limits.viscous) which = "viscous";
      else if (stable == limits.drag) which = "explicit drag";
      else if (stable == limits.force) which = "force";
      else if (stable == limits.overdamped) which = "overdamped";
      const std::string msg = "time step " + formatSeconds(dt) + " exceeds the " + which + " stability limit " +
                              formatSeconds(stable) + " of the " + toString(p.integrator) + " integrator";
      if (p.stepLimitPolicy == StepLimitPolicy::Refuse) throw SimulationError(msg);
      if (warnings_.empty() || warnings_.back() != msg + "; clamped") warnings_.push_back(msg + "; clamped");
      dt = stable;
    }
  } else {
    dt = std::min(stable, limits.displacement);
    if (p.maxTimeStep) dt = std::min(dt, *p.maxTimeStep);
  }
  if (!std::isfinite(dt) || dt <= 0) throw SimulationError("no finite time step: nothing limits it (no fluid, no forces)");
  if (p.integrator == Integrator::CentralDifference) {
    // Eq. 8 uses one constant step; start the previous positions consistently with the velocities.
    centralDifferenceStep_ = dt;
    for (std::size_t i = 0; i < fluid_.size(); ++i) {
      fluid_.xp[i] = fluid_.x[i] - fluid_.vx[i] * dt;
      fluid_.yp[i] = fluid_.y[i] - fluid_.vy[i] * dt;
      fluid_.zp[i] = fluid_.z[i] - fluid_.vz[i] * dt;
    }
  }
  return dt;
}

double Simulation::nextTimeStep() const {
  if (parameters_.integrator == Integrator::CentralDifference && centralDifferenceStep_ > 0) return centralDifferenceStep_;
  const StepLimits l = currentLimits();
  if (parameters_.fixedTimeStep) return std::min(*parameters_.fixedTimeStep, l.stable());
  const double dt = std::min(l.stable(), l.displacement);
  return parameters_.maxTimeStep ? std::min(dt, *parameters_.maxTimeStep) : dt;
}

// ------------------------------------------------------------------------------------------------
// Integration
// ------------------------------------------------------------------------------------------------

void Simulation::integrate(double dt) {
  const ModelParameters& p = parameters_;
  const std::size_t n = fluid_.size();
  const bool drag = p.viscosityModel == ViscosityModel::Drag;
  FluidParticles& f = fluid_;
  switch (p.integrator) {
  case Integrator::CentralDifference: {
    // Eq. 8 with a_i = a_other - gamma v_i and v_i = (r+ - r-) / (2 dt), solved for r+ per particle
    // (the drag acts on a particle's own velocity only, so the system is diagonal):
    //   r+ = [2 r - (1 - gamma dt/2) r- + dt^2 a_other] / (1 + gamma dt/2)
#pragma omp parallel for schedule(static)
    for (std::size_t i = 0; i < n; ++i) {
      const double gdt2 = drag ? 0.5 * dt * p.dragRate(f.mass[i], f.density[i]) : 0.0;
      const double inv = 1.0 / (1.0 + gdt2), c = 1.0 - gdt2, dt2 = dt * dt;
      const double nx = (2 * f.x[i] - c * f.xp[i] + dt2 * f.ax[i]) * inv;
      const double ny = (2 * f.y[i] - c * f.yp[i] + dt2 * f.ay[i]) * inv;
      const double nz = (2 * f.z[i] - c * f.zp[i] + dt2 * f.az[i]) * inv;
      f.vx[i] = (nx - f.xp[i]) / (2 * dt);
      f.vy[i] = (ny - f.yp[i]) / (2 * dt);
      f.vz[i] = (nz - f.zp[i]) / (2 * dt);
      f.xp[i] = f.x[i]; f.yp[i] = f.y[i]; f.zp[i] = f.z[i];
      f.x[i] = nx; f.y[i] = ny; f.z[i] = nz;
    }
    break;
  }
  case Integrator::Explicit: {
    // Symplectic Euler: v += dt (a - gamma v); r += dt v.
#pragma omp parallel for schedule(static)
    for (std::size_t i = 0; i < n; ++i) {
      const double g = drag ? p.dragRate(f.mass[i], f.density[i]) : 0.0;
      f.vx[i] += dt * (f.ax[i] - g * f.vx[i]);
      f.vy[i] += dt * (f.ay[i] - g * f.vy[i]);
      f.vz[i] += dt * (f.az[i] - g * f.vz[i]);
      f.xp[i] = f.x[i]; f.yp[i] = f.y[i]; f.zp[i] = f.z[i];
      f.x[i] += dt * f.vx[i]; f.y[i] += dt * f.vy[i]; f.z[i] += dt * f.vz[i];
    }
    break;
  }
  case Integrator::Overdamped: {
    // Creeping flow: inertia negligible (gamma dt >> 1), so the drag balances the other forces.
#pragma omp parallel for schedule(static)
    for (std::size_t i = 0; i < n; ++i) {
      const double invG = 1.0 / p.dragRate(f.mass[i], f.density[i]);
      f.vx[i] = f.ax[i] * invG; f.vy[i] = f.ay[i] * invG; f.vz[i] = f.az[i] * invG;
      f.xp[i] = f.x[i]; f.yp[i] = f.y[i]; f.zp[i] = f.z[i];
      f.x[i] += dt * f.vx[i]; f.y[i] += dt * f.vy[i]; f.z[i] += dt * f.vz[i];
    }
    break;
  }
  }
}

void Simulation::applyBoundaries() {
  const std::size_t n = fluid_.size();
  FluidParticles& f = fluid_;
  std::vector<std::uint8_t> keep;
  std::size_t leaving = 0;
  double* pos[3] = {f.x.data(), f.y.data(), f.z.data()};
  double* prev[3] = {f.xp.data(), f.yp.data(), f.zp.data()};
  for (int a = 0; a < 3; ++a) {
    const double lo = domain_.lower[a], hi = domain_.upper[a], L = extent_[a];
    if (domain_.periodic[a]) {
      // Re-enter on the opposite side with the same velocity and density (the paper, after Jiang et al.)
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
  if (leaving) {
    f.compact(keep);
    escaped_ += leaving;
    listsValid_ = false;
  }
}

std::string Simulation::describeParticle(std::size_t i) const {
  std::ostringstream s;
  s.precision(4);
  s << "fluid particle #" << fluid_.id[i] << " at (" << fluid_.x[i] * 1e3 << ", " << fluid_.y[i] * 1e3 << ", "
    << fluid_.z[i] * 1e3 << ") mm";
  return s.str();
}

void Simulation::checkHealth(double dt) const {
  const std::size_t n = fluid_.size();
  const double vmax = parameters_.runawaySpeedFactor * parameters_.soundSpeed;
  std::size_t firstBad = n;
#pragma omp parallel for schedule(static) reduction(min : firstBad)
  for (std::size_t i = 0; i < n; ++i) {
    const double v2 = fluid_.vx[i] * fluid_.vx[i] + fluid_.vy[i] * fluid_.vy[i] + fluid_.vz[i] * fluid_.vz[i];
    const bool finite = std::isfinite(fluid_.x[i]) && std::isfinite(fluid_.y[i]) && std::isfinite(fluid_.z[i]) &&
                        std::isfinite(v2) && std::isfinite(fluid_.density[i]);
    if (!finite || v2 > vmax * vmax) firstBad = std::min(firstBad, i);
  }
  if (firstBad == n) return;
  const std::size_t i = firstBad;
  std::ostringstream s;
  s.precision(4);
  s << "simulation unstable at step " << statistics_.steps + 1 << " (t = " << time_ << " s, dt = " << dt << " s): ";
  const double v = std::sqrt(fluid_.vx[i] * fluid_.vx[i] + fluid_.vy[i] * fluid_.vy[i] + fluid_.vz[i] * fluid_.vz[i]);
  if (!std::isfinite(v) || !std::isfinite(fluid_.x[i]) || !std::isfinite(fluid_.density[i]))
    s << describeParticle(i) << " has a non-finite position, velocity or density";
  else
    s << describeParticle(i) << " moves at " << v << " m/s, over " << parameters_.runawaySpeedFactor
      << " times the speed of sound (runaway)";
  const StepLimits l = currentLimits();
  s << "; " << toString(parameters_.integrator) << " stability limit " << l.stable()
    << " s: reduce the time step or check the scene";
  throw SimulationError(s.str());
}

double Simulation::step() {
  if (fluid_.size() == 0) throw SimulationError("no fluid particles to simulate");
  updateDensityAndPressure();
  updateAccelerations();
  const double dt = chooseTimeStep(currentLimits());
  integrate(dt);
  checkHealth(dt);
  applyBoundaries();
  time_ += dt;
  ++statistics_.steps;
  statistics_.smallestStep = statistics_.steps == 1 ? dt : std::min(statistics_.smallestStep, dt);
  statistics_.largestStep = std::max(statistics_.largestStep, dt);
  return dt;
}

double Simulation::kineticEnergy() const {
  double e = 0;
  for (std::size_t i = 0; i < fluid_.size(); ++i)
    e += 0.5 * fluid_.mass[i] * (fluid_.vx[i] * fluid_.vx[i] + fluid_.vy[i] * fluid_.vy[i] + fluid_.vz[i] * fluid_.vz[i]);
  return e;
}

} // namespace cementsph::sph
